"""Water drops on a windshield: drops that arrive with the rain, slide, merge and are swept by
wipers, drawn as refracting 2D metaballs over a frame.

The method is Gotou, Tanaka & Sagawa's, *Real-Time Rendering of Flow of Water Drops on a
Windshield* (Meijo University): a mesh model of 2 mm cells with random affinities away from
the wipers (one drop per cell, fusion, meandering steps, trails that shrink and vanish), a
particle model of equal particles near each wiper (pushed apart with a penalty term, pushed by
the blade), and their drawing as 2D metaballs N = 1/(1 + (h/R)^4) summed into a height map,
compressed, thresholded at 0.5, whose normals refract the frame behind the glass. A drop slides
only above Furmidge's critical size (:func:`furmidge_critical`); the rain arrives as
Marshall-Palmer drops times their fall speed (and the car's speed) through the glass.

Glass coordinates are millimetres: x across the glass from its left edge, y down its slope from
its top edge.

The renderer draws the glass in the core, as the last stage of the frame
(``Weather(windshield=...)``): the drops refract everything behind them and the blades are drawn
over them, on every output, in the one core call of the frame. A preset's glass is drawn at the
frame's ``time_s`` from its warm state (:func:`clock`): the preset's steady glass drawn once per
(preset, seed) (:func:`steady`), then advanced by ``time_s`` modulo :data:`EPOCH_PERIODS`
periods, so the frames of a clip show the drops arriving, sliding and being swept, and any frame
costs at most a period of stepping once the epoch's checkpoints are made.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import in_range, integer, real, values

__all__ = [
    "EPOCH_PERIODS",
    "PRESETS",
    "SETTLED_PERIODS",
    "STEADY_PRESETS",
    "WARM_UP_PERIODS",
    "Windshield",
    "clock",
    "draw_gpu",
    "frame_glass",
    "furmidge_critical",
    "metaball_height_map",
    "normals",
    "preset",
    "refract",
    "steady",
    "steady_table",
    "warm",
]

WATER_INDEX: Final = 1.333
"""Water's refractive index (20 C, 589 nm, rounded)."""

PRESETS: Final[dict[str, dict[str, Any]]] = {
    "drizzle": {"rain_rate_mm_h": 2.0, "wipers": 2, "wiper_period_s": 2.5, "car_speed_m_s": 10.0},
    "rain": {"rain_rate_mm_h": 10.0, "wipers": 2, "wiper_period_s": 1.5, "car_speed_m_s": 14.0},
    "downpour": {"rain_rate_mm_h": 30.0, "wipers": 2, "wiper_period_s": 1.0, "car_speed_m_s": 14.0},
    "parked": {"rain_rate_mm_h": 10.0, "wipers": 0, "car_speed_m_s": 0.0},
}
"""Named windshields: ``Weather(windshield="rain")``, :func:`preset`."""


def furmidge_critical(advancing_deg: float, receding_deg: float, glass_tilt_deg: float) -> tuple[float, float]:
    """The critical drop on inclined glass, by Furmidge's criterion.

    ρ g V sin α = k σ 2a (cos θ_R − cos θ_A) with k = 1, the drop a spherical cap at the mean
    contact angle θ = (θ_A + θ_R)/2 on its base radius a, V = π a³ (2 − 3cos θ + cos³ θ) / (3 sin³ θ).

    Parameters
    ----------
    advancing_deg : float
        Advancing contact angle θ_A, deg, in (0, 180).
    receding_deg : float
        Receding contact angle θ_R, deg, in (0, 180).
    glass_tilt_deg : float
        Glass inclination α from the horizontal, deg, in [0, 90].

    Returns
    -------
    (float, float)
        The critical base radius a, m (inf on level glass), and the critical volume V, m^3.
    """
    return _core.furmidge_critical(
        in_range("advancing_deg", advancing_deg), in_range("receding_deg", receding_deg), in_range("glass_tilt_deg", glass_tilt_deg)
    )


class Windshield:
    """A windshield in the rain: its glass, drops and wipers, stepped in time.

    Parameters
    ----------
    rain_rate_mm_h : float
        Rain rate, mm/h, in [0, 500].
    glass_width_mm : float
        Glass width, mm, in [10, 4000] (default 1400); with ``cell_mm``, at most 4e6 cells.
    glass_height_mm : float
        Glass height along its slope, mm, in [10, 4000] (default 800); with ``cell_mm``, at
        most 4e6 cells.
    glass_tilt_deg : float
        Inclination from the horizontal, deg, in [0, 90] (default 30, a car's windshield).
    car_speed_m_s : float
        The car's speed, m/s, in [0, 80]: the airflow pushes drops up the glass
        (½ ρ_air C_d (0.5 v)² of the drop's frontal area) and the glass sweeps up more rain.
    wipers : int
        Number of wipers, in [0, 2]: none, one centred, or two (a left-hand-drive layout).
    wiper_period_s : float
        The wipers' period, there and back, s, in [0.2, 60].
    wiper_angles_deg : (float, float)
        The sweep, (from, to), deg from the glass's horizontal towards its top, each in [-30, 210].
    advancing_deg : float
        Advancing contact angle of water on the glass, deg, in (0, 180) (default 40).
    receding_deg : float
        Receding contact angle, deg, in (0, 180), below ``advancing_deg`` (default 20). The
        40/20 pair is an assumed clean glass; a coated glass is nearer 110/90.
    cell_mm : float
        The mesh model's cell, mm, in [0.5, 10] (the paper's 2 mm). The glass is at most 4e6
        cells (``glass_width_mm / cell_mm × glass_height_mm / cell_mm``): a 4000 × 4000 mm
        glass takes cells of 2 mm or more, 0.5 mm cells a glass of up to 1 m²; beyond it a
        ValueError names this parameter and the least cell for the glass.
    particle_radius_mm : float
        The particle model's particle base radius, mm, in [0.2, 5] (default 1).
    seed : int
        Seed of the affinities and of every step's draws, in [0, 2^64): the same seed and the
        same calls give the same bits.
    state : dict, optional
        A state from :meth:`state` to resume from (same other parameters).

    Examples
    --------
    >>> w = Windshield(rain_rate_mm_h=10.0, glass_width_mm=300.0, glass_height_mm=200.0, wipers=0)
    >>> w.step(0.5)
    >>> xy, radius_mm, kind = w.drops()
    >>> bool(len(xy) > 0 and (kind != 2).all())  # no particles without wipers
    True
    """

    def __init__(
        self,
        rain_rate_mm_h: float = 10.0,
        *,
        glass_width_mm: float = 1400.0,
        glass_height_mm: float = 800.0,
        glass_tilt_deg: float = 30.0,
        car_speed_m_s: float = 0.0,
        wipers: int = 2,
        wiper_period_s: float = 1.5,
        wiper_angles_deg: tuple[float, float] = (5.0, 120.0),
        advancing_deg: float = 40.0,
        receding_deg: float = 20.0,
        cell_mm: float = 2.0,
        particle_radius_mm: float = 1.0,
        seed: int = 0,
        state: dict[str, Any] | None = None,
    ) -> None:
        integer("wipers", wipers, int(_core.RANGES["wipers"][0]), int(_core.RANGES["wipers"][1]))
        integer("seed", seed, 0, 2**64 - 1)
        if not isinstance(wiper_angles_deg, (tuple, list, np.ndarray)) or len(wiper_angles_deg) != 2:
            raise TypeError(f"wiper_angles_deg must be (from, to), two numbers, got {wiper_angles_deg!r}")
        self.params: dict[str, Any] = dict(
            rain_rate_mm_h=in_range("rain_rate_mm_h", rain_rate_mm_h),
            glass_width_mm=in_range("glass_width_mm", glass_width_mm),
            glass_height_mm=in_range("glass_height_mm", glass_height_mm),
            glass_tilt_deg=in_range("glass_tilt_deg", glass_tilt_deg),
            car_speed_m_s=in_range("car_speed_m_s", car_speed_m_s),
            wipers=int(wipers),
            wiper_period_s=in_range("wiper_period_s", wiper_period_s),
            wiper_angles_deg=(in_range("wiper_angles_deg", wiper_angles_deg[0]), in_range("wiper_angles_deg", wiper_angles_deg[1])),
            advancing_deg=in_range("advancing_deg", advancing_deg),
            receding_deg=in_range("receding_deg", receding_deg),
            cell_mm=in_range("cell_mm", cell_mm),
            particle_radius_mm=in_range("particle_radius_mm", particle_radius_mm),
            seed=int(seed),
        )
        self._core = _core.Windshield(**self.params, state=state)

    def step(self, dt_s: float) -> None:
        """Advance the simulation.

        Parameters
        ----------
        dt_s : float
            Time step, s, in (0, 1e7]; split internally into steps of at most 1/60 s (so a
            step's cost grows with it: an hour of glass is 216 000 internal steps).
        """
        self._core.step(in_range("dt_s", dt_s))

    @property
    def t_s(self) -> float:
        """Simulated time, s."""
        return float(self._core.t_s)

    def drops(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.uint8]]:
        """Every drop: positions (N, 2) in glass mm (x, y down the slope), base radii (N,) mm,
        kinds (N,) uint8: 0 a mesh drop, 1 a trail drop, 2 a particle (near a wiper)."""
        return self._core.drops()

    def metaballs(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Every metaball, mm: centres (N, 2) and radii (N,); the drops' main ones and, for
        0.4 s after an impact, three sub-metaballs drifting into each new drop."""
        return self._core.metaballs()

    def blades(self) -> list[tuple[tuple[float, float], float, float, float]]:
        """The wipers now: (pivot (x, y) mm, angle rad from the glass's horizontal towards its
        top, length mm, width mm) each."""
        return self._core.blades()

    def water_kg(self) -> dict[str, float]:
        """The water balance, kg: ``on_glass`` + ``swept_off`` (left across an edge, swept or
        run off) + ``evaporated`` (the trails) = ``arrived``, to rounding."""
        on, arrived, off, evap = self._core.water_kg()
        return {"on_glass": on, "arrived": arrived, "swept_off": off, "evaporated": evap}

    def arrival_kg_per_s(self) -> float:
        """The expected arrival of water on the whole glass, kg/s."""
        return float(self._core.arrival_kg_per_s())

    def state(self) -> dict[str, Any]:
        """The state (drops, particles, time, counters): ``Windshield(..., state=s)`` resumes it."""
        return dict(self._core.state())

    def save(self, path: str | Path) -> None:
        """Save the parameters and the state to ``path`` (``.npz``)."""
        s = self.state()
        np.savez(
            path,
            drops=s["drops"],
            particles=s["particles"],
            scalars=np.array([s["t_s"], s["arrived_kg"], s["swept_off_kg"], s["evaporated_kg"]]),
            steps=np.array([s["steps"]], np.uint64),
            params=np.array(repr(self.params)),
        )

    @classmethod
    def load(cls, path: str | Path) -> Windshield:
        """A windshield saved by :meth:`save`.

        Raises
        ------
        FileNotFoundError, PermissionError, IsADirectoryError
            When ``path`` cannot be opened.
        ValueError
            When the file is not what :meth:`save` writes (naming the file and what it lacks),
            or its parameters or state are outside their ranges.
        """
        import ast
        import zipfile

        expected = "a windshield saved by Windshield.save (an .npz of params, scalars, steps, drops and particles)"

        def refuse(why: str) -> ValueError:
            return ValueError(f"{os.fspath(path)!r} is not {expected}: {why}")

        try:
            z = np.load(path, allow_pickle=False)
        except (FileNotFoundError, PermissionError, IsADirectoryError):
            raise
        except EOFError:
            raise refuse("it is empty") from None
        except (ValueError, OSError, zipfile.BadZipFile):  # numpy's pickle hint is no help here
            raise refuse("its bytes are not an .npz archive") from None
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise refuse("it holds one array, not an .npz archive")
        with z:
            missing = [k for k in ("params", "scalars", "steps", "drops", "particles") if k not in z.files]
            if missing:
                raise refuse(f"it has no {', '.join(missing)}")
            try:
                params = ast.literal_eval(str(z["params"]))
                t, arrived, off, evap = (float(v) for v in z["scalars"])
                state = {
                    "t_s": t,
                    "steps": int(z["steps"][0]),
                    "drops": np.ascontiguousarray(z["drops"]),
                    "particles": np.ascontiguousarray(z["particles"]),
                    "arrived_kg": arrived,
                    "swept_off_kg": off,
                    "evaporated_kg": evap,
                }
            except (ValueError, TypeError, SyntaxError, IndexError, zipfile.BadZipFile, EOFError, OSError) as e:
                raise refuse(f"{type(e).__name__}: {e}") from None
        if not isinstance(params, dict) or not all(isinstance(k, str) for k in params):
            raise refuse(f"its params are {type(params).__name__}, not a dict of the constructor's keywords")
        return cls(**params, state=state)


def preset(name: str, *, seed: int = 0) -> Windshield:
    """A new windshield of a named preset (:data:`PRESETS`)."""
    if name not in PRESETS:
        raise ValueError(f"windshield = {name!r} is not a preset: use one of {', '.join(map(repr, PRESETS))}")
    return Windshield(**PRESETS[name], seed=seed)


WARM_UP_PERIODS: Final = 4
"""The wiper periods :func:`clock` steps from dry glass for a preset whose steady table was
measured for other parameters than its own (none is: :data:`STEADY_PRESETS`): a glass still
filling (about 2 s of stepping for the ``rain`` preset on 2 cores)."""

SETTLED_PERIODS: Final = 40
"""The wiper periods after which the ``rain`` preset's glass has settled: its held water stays in
a steady band from there (``benches/results/windshield_27.md``; ``downpour`` settles from about
20 periods, ``drizzle`` from about 120)."""


EPOCH_PERIODS: Final = 4
"""A preset's frames repeat every this many wiper periods (6 s for the ``rain`` preset): within
it a clip's frames show the same glass moving on; each frame costs at most one period of
stepping once the epoch's checkpoints are made (``skyfall_core::windshield::clock``)."""

_DATA = Path(__file__).parent / "data"


def _period_s(w: Windshield) -> float:
    return float(w.params.get("wiper_period_s", 1.5)) if w.params["wipers"] else 2.0


def _measured_for_now(name: str) -> bool:
    """Whether preset ``name`` has a steady table measured for its parameters now (reading the
    table's parameters alone; a preset's are :class:`Windshield`'s defaults and its own)."""
    import ast
    import inspect

    path = _DATA / f"windshield_steady_{name}.npz"
    if name not in PRESETS or not path.is_file():
        return False
    defaults = {
        k: p.default
        for k, p in inspect.signature(Windshield.__init__).parameters.items()
        if p.default is not inspect.Parameter.empty and k not in ("seed", "state")
    }
    with np.load(path, allow_pickle=False) as z:
        measured = ast.literal_eval(str(z["params"]))
    return bool(measured == {**defaults, **PRESETS[name]})


@lru_cache(maxsize=None)
def _steady_table(name: str) -> dict[str, Any] | None:
    """A preset's steady table (``benches/windshield_steady.py``), read at its first draw, or
    None where it has none or it was measured for other parameters than the preset's now."""
    if not _measured_for_now(name):
        return None
    with np.load(_DATA / f"windshield_steady_{name}.npz", allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


STEADY_PRESETS: Final = tuple(n for n in PRESETS if _measured_for_now(n))
"""The presets whose steady state is tabulated for their parameters now (all of them; a table
measured for other parameters is left out, and :func:`clock` steps that preset from dry glass):
:func:`steady` draws it; :func:`clock` starts from it."""


STEADY_CELL_MM: Final = 10.0
"""The squares of a steady table, mm: each kind's mean number of drops per square."""

STEADY_BLOCK: Final = 4
"""Squares per side of the blocks that share a mass histogram in a steady table."""

STEADY_MASS_EDGES_KG: Final = np.logspace(-10.0, -3.0, 57)
"""A steady table's mass bins, kg: eight a decade from 1e-10 to 1e-3 kg."""


def steady_table(states: list[Windshield]) -> dict[str, Any]:
    """The statistics a steady glass is drawn from (:func:`steady`), pooled from states of one
    glass, each at the start of a wiper period after it has settled.

    Parameters
    ----------
    states : list of Windshield
        At least one, all with the same parameters but the seed.

    Returns
    -------
    dict
        ``counts`` (3, ny, nx): the mean number of mesh drops, trail drops and particles per
        :data:`STEADY_CELL_MM` square; ``mass_hist`` (3, by, bx, bins): their masses over
        blocks of :data:`STEADY_BLOCK` squares in :data:`STEADY_MASS_EDGES_KG`; ``cell_mm``,
        ``block``, ``mass_edges_kg``, ``snapshots``, ``from_period`` (the first state's wiper
        periods into the rain); ``params`` (the glass's, seed left out).
    """
    if not states or not all(isinstance(w, Windshield) for w in states):
        raise TypeError("states must be a non-empty list of Windshield")
    params = {k: v for k, v in states[0].params.items() if k != "seed"}
    if any({k: v for k, v in w.params.items() if k != "seed"} != params for w in states):
        raise ValueError("states must all have the same parameters but the seed")
    width, height = params["glass_width_mm"], params["glass_height_mm"]
    nx, ny = int(np.ceil(width / STEADY_CELL_MM)), int(np.ceil(height / STEADY_CELL_MM))
    bx, by = -(-nx // STEADY_BLOCK), -(-ny // STEADY_BLOCK)
    nb = len(STEADY_MASS_EDGES_KG) - 1
    counts = np.zeros((3, ny, nx))
    hist = np.zeros((3, by, bx, nb))
    for w in states:
        st = w.state()
        d, p = st["drops"], st["particles"]
        xy = np.concatenate([d[:, :2], p[:, :2]])
        kind = np.concatenate([np.where(d[:, 4] != 0, 1, 0), np.full(len(p), 2)])
        mass = np.concatenate([d[:, 2], p[:, 2]])
        cx = np.clip((xy[:, 0] // STEADY_CELL_MM).astype(int), 0, nx - 1)
        cy = np.clip((xy[:, 1] // STEADY_CELL_MM).astype(int), 0, ny - 1)
        b = np.clip(np.searchsorted(STEADY_MASS_EDGES_KG, mass, side="right") - 1, 0, nb - 1)
        np.add.at(counts, (kind, cy, cx), 1.0)
        np.add.at(hist, (kind, cy // STEADY_BLOCK, cx // STEADY_BLOCK, b), 1.0)
    return {
        "cell_mm": np.array(STEADY_CELL_MM),
        "block": np.array(STEADY_BLOCK),
        "mass_edges_kg": STEADY_MASS_EDGES_KG.copy(),
        "counts": (counts / len(states)).astype(np.float32),
        "mass_hist": hist.astype(np.uint32),
        "snapshots": np.array(len(states)),
        "from_period": np.array(min(int(round(w.t_s / _period_s(w))) for w in states)),
        "params": np.array(repr(params)),
    }


def steady(glass: str | Windshield, *, seed: int = 0, table: dict[str, Any] | None = None) -> Windshield:
    """A glass in its steady state at the start of a wiper period, drawn statistically
    (0.04-0.2 s) instead of stepped there (a minute or more).

    A preset's table (``python/skyfall/data/windshield_steady_<name>.npz``, made by
    ``benches/windshield_steady.py`` with :func:`steady_table`) pools the states of long
    simulations of the preset once settled (seeds 1, 3 and 4; periods 36-56 of ``rain`` and
    ``downpour``, 120-160 of ``drizzle``, 300-350 of ``parked``): for mesh drops, trail drops
    and the wipers' particles, the mean number in each 10 mm square of the glass and the
    histogram of their masses over 40 mm blocks (log bins, 8 a decade). A draw takes a Poisson
    number of each in each square at uniform points, masses from its block's histogram
    (log-uniform within a bin), places mesh and trail drops largest first where they touch no
    other mesh drop and find their 2 mm cell empty, as the simulation keeps them, and spaces the
    particles by the wipers' push-apart (``skyfall_core::windshield::steady``). Against long
    simulations of seeds the table did not pool, its held water and drop-size histogram agree
    within their spread between periods (``tests/test_windshield_steady.py``,
    ``benches/results/windshield_steady_check_<name>.json``). What a draw does not have: the trails' lines (trail drops
    lie scattered until sliding drops lay new ones) and the sub-metaballs of the last 0.4 s of
    impacts.

    Parameters
    ----------
    glass : str or Windshield
        A preset in :data:`STEADY_PRESETS`, or a windshield whose parameters ``table`` was
        measured for (its state is not used).
    seed : int
        The new glass's seed, in [0, 2^64): the draw's and the simulation's after it.
    table : dict, optional
        A :func:`steady_table` (a preset's own by default).

    Returns
    -------
    Windshield
        As many wiper periods into the rain as the first state the table pooled
        (``table["from_period"]``: 36 for ``rain`` and ``downpour``, 120 for ``drizzle``, 300
        for ``parked``), the wipers at the start of a sweep.
    """
    integer("seed", seed, 0, 2**64 - 1)
    if isinstance(glass, Windshield):
        if table is None:
            raise ValueError("steady(glass) of a Windshield needs its table=steady_table(...)")
        w = Windshield(**{**glass.params, "seed": int(seed)})
    elif isinstance(glass, str) and glass in PRESETS:
        table = table if table is not None else _steady_table(glass)
        if table is None:
            raise ValueError(f"windshield = {glass!r} has no steady table: use one of {', '.join(map(repr, STEADY_PRESETS))}")
        w = preset(glass, seed=seed)
    else:
        raise ValueError(f"windshield = {glass!r} is not a preset: use one of {', '.join(map(repr, STEADY_PRESETS))}")
    period = _period_s(w)
    periods = int(table["from_period"])
    core, _report = w._core.drawn_steady(
        cell_mm=float(table["cell_mm"]),
        block=int(table["block"]),
        mass_edges_kg=np.ascontiguousarray(table["mass_edges_kg"], np.float64),
        counts=np.ascontiguousarray(table["counts"], np.float64),
        mass_weights=np.ascontiguousarray(np.asarray(table["mass_hist"], np.float64).ravel()),
        t_s=periods * period,
    )
    out = Windshield.__new__(Windshield)
    out.params = dict(w.params)
    out._core = core
    return out


@lru_cache(maxsize=4)
def _clock(name: str, seed: int, warm_up_periods: int | None) -> _core.GlassClock:
    if warm_up_periods is None:
        w = steady(name, seed=seed)
    else:
        w = preset(name, seed=seed)
        for _ in range(warm_up_periods):
            w.step(_period_s(w))
    return _core.GlassClock(w._core, _period_s(w), EPOCH_PERIODS)


def clock(name: str, *, seed: int = 0, warm_up_periods: int | None = None) -> _core.GlassClock:
    """A preset's glass on the frames' clock: ``clock(...).at(t_s)`` is the glass at frame time
    ``t_s``, the same bits whatever frames were drawn before.

    The warm state is the preset's steady glass drawn statistically (:func:`steady`) where the
    preset has a table (:data:`STEADY_PRESETS`), else the glass after :data:`WARM_UP_PERIODS`
    wiper periods (2 s each without wipers) stepped from dry; ``warm_up_periods`` asks for that
    many stepped periods instead. It is made once per (name, seed, warm_up_periods) and cached
    (4 clocks); the glass at ``t_s`` is that state advanced by ``t_s`` modulo
    :data:`EPOCH_PERIODS` periods, on a fixed grid of steps (at most 1/60 s) from each period's
    start: the state at each period's start is made once and kept, and the last state a frame
    reached, so the next frame of a clip steps only the time between them.

    Parameters
    ----------
    name : str
        A preset, :data:`PRESETS`.
    seed : int
        The windshield's seed, in [0, 2^64).
    warm_up_periods : int or None
        None (default) for the drawn steady glass where there is one, else periods stepped
        from dry glass once before the clock, in [1, 100].
    """
    if name not in PRESETS:
        raise ValueError(f"windshield = {name!r} is not a preset: use one of {', '.join(map(repr, PRESETS))}")
    integer("seed", seed, 0, 2**64 - 1)
    if warm_up_periods is not None:
        integer("warm_up_periods", warm_up_periods, 1, 100)
        periods: int | None = int(warm_up_periods)
    else:
        periods = None if name in STEADY_PRESETS else WARM_UP_PERIODS
    return _clock(name, int(seed), periods)


def warm(name: str, t_s: float, *, seed: int = 0, warm_up_periods: int | None = None) -> Windshield:
    """A preset's windshield as a frame at ``t_s`` draws it: ``clock(name, ...).at(t_s)``.

    The glass is the warm state advanced by ``t_s`` modulo :data:`EPOCH_PERIODS` periods (see
    :func:`clock`): the wipers stand where they would at ``t_s``, and the drops are the glass
    after those periods (not the one exact history of ``t_s`` seconds of rain). The warm state
    of a preset in :data:`STEADY_PRESETS` is its steady glass drawn statistically
    (:func:`steady`): the glass the blades do not reach (half of the presets' glass) full of
    drops up to the size at which they slide (Furmidge's criterion with the airflow), as the
    ``rain`` preset's glass holds it from some 40 periods of rain on
    (``benches/results/windshield_27.md``). ``warm_up_periods=n`` steps ``n`` periods from dry
    glass instead (40 periods of the ``rain`` preset take about a minute).

    Parameters
    ----------
    name : str
        A preset, :data:`PRESETS`.
    t_s : float
        Time into the rain, s, in [-1e7, 1e7].
    seed : int
        The windshield's seed.
    warm_up_periods : int or None
        None (default) for the drawn steady glass where there is one; else periods stepped
        from dry glass once before the cache, in [1, 100].
    """
    t = in_range("time_s", t_s)
    c = clock(name, seed=seed, warm_up_periods=warm_up_periods)
    w = Windshield.__new__(Windshield)
    w.params = dict(preset(name, seed=seed).params)
    w._core = c.at(t)
    return w


def metaball_height_map(
    centers_px: Any, radii_px: Any, shape: tuple[int, int], *, compress: bool = True
) -> NDArray[np.float32]:
    """Gotou, Tanaka & Sagawa's metaball field, summed and compressed.

    Each metaball adds N = 1/(1 + (h/R)^4) (h the distance of a pixel centre, at +0.5, from its
    centre) out to h = 4R (N = 1/257 there); with ``compress``, peaks are compressed five times,
    V <- 0.3 (V - V0) + V0 where V > V0, V0 = 0.5, 0.6, ..., 0.9. The drops are where V > 0.5:
    one metaball alone thresholds to a disk of radius R.

    Parameters
    ----------
    centers_px : array_like, shape (N, 2)
        Centres (x, y), px, finite.
    radii_px : array_like, shape (N,)
        Radii R, px, each in (0, 1e4].
    shape : (int, int)
        (H, W) of the map, each in [1, 16384].
    compress : bool
        Apply the paper's compression (default True).

    Returns
    -------
    ndarray of float32, shape (H, W)
    """
    c = values("centers_px", centers_px, shape="(N, 2)")
    r = values("radii_px", radii_px, shape="(N,)")
    if not isinstance(shape, (tuple, list)) or len(shape) != 2:
        raise TypeError(f"shape must be (H, W), two ints, got {shape!r}")
    h, w = integer("height", shape[0], 1, 16384), integer("width", shape[1], 1, 16384)
    return _core.metaball_height_map(c, r, w, h, bool(compress))


def normals(height_map: NDArray[np.float32], slope_px: float) -> NDArray[np.float32]:
    """Unit normals (x, y, z) of the water surface, (H, W, 3) float32: central differences of
    the field, n ∝ (−s ∂V/∂x, −s ∂V/∂y, 1) with s = ``slope_px`` px of height per unit of V
    in [0, 1e5] px; ``height_map`` is (H, W), finite."""
    s = real("slope_px", slope_px)
    return _core.metaball_normals(values("height_map", height_map, finite=True, shape="(H, W)"), s)


def refract(
    frame: NDArray[np.float32],
    height_map: NDArray[np.float32],
    *,
    focal_px: float,
    slope_px: float,
    refraction: Literal["offset", "snell"] = "offset",
    principal_px: tuple[float, float] | None = None,
    index: float = WATER_INDEX,
    lookup_px: int = 64,
    blur_px: float = 0.0,
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """The frame seen through the drops of a height map.

    Parameters
    ----------
    frame : ndarray of float32, shape (H, W, 3)
        What lies behind the glass (linear light).
    height_map : ndarray of float32, shape (H, W)
        :func:`metaball_height_map`'s field.
    focal_px : float
        The camera's focal length, px.
    slope_px : float
        Height of the water surface, px per unit of the field (sets the normals' tilt).
    refraction : {"offset", "snell"}
        ``"offset"`` (default, the paper's): the background at p − (η − 1) f (n_x, n_y), the
        deviation of a thin water prism; ``"snell"``: the pixel's ray refracted into the water
        at the flat glass and out at the curved surface, exactly.
    principal_px : (float, float), optional
        The principal point, px (default the frame's centre).
    index : float
        Water's refractive index η (default 1.333).
    lookup_px : int
        The short side of the box-averaged copy the drops look into (the paper's 64; 0: the
        frame itself).
    blur_px : float
        The drops' blur circle, px (a camera focused beyond the glass), 0: sharp.

    Returns
    -------
    (ndarray of float32 (H, W, 3), ndarray of float32 (H, W))
        The frame with its drops, and their (sharp, anti-aliased) coverage.
    """
    frame = np.ascontiguousarray(frame, np.float32)
    h, w = frame.shape[:2]
    pp = (w / 2.0, h / 2.0) if principal_px is None else (float(principal_px[0]), float(principal_px[1]))
    return _core.refract_through_drops(
        frame,
        np.ascontiguousarray(height_map, np.float32),
        refraction=str(refraction),
        focal_px=float(focal_px),
        principal_px=pp,
        index=float(index),
        slope_px=float(slope_px),
        lookup_px=int(lookup_px),
        blur_px=float(blur_px),
    )


def draw_gpu(
    device: Any,
    centers_px: Any,
    radii_px: Any,
    frame: NDArray[np.float32],
    *,
    focal_px: float,
    slope_px: float,
    refraction: Literal["offset", "snell"] = "offset",
    principal_px: tuple[float, float] | None = None,
    index: float = WATER_INDEX,
    lookup_px: int = 64,
    compress: bool = True,
) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.float32]]:
    """:func:`metaball_height_map` and :func:`refract` (in focus) in one GPU pass on
    ``device`` (a GPU :class:`skyfall.Renderer`'s device): (field, rgb, coverage), the CPU's
    within f32 rounding (``rust/skyfall-gpu/tests/windshield_gpu.rs``)."""
    frame = np.ascontiguousarray(frame, np.float32)
    h, w = frame.shape[:2]
    pp = (w / 2.0, h / 2.0) if principal_px is None else (float(principal_px[0]), float(principal_px[1]))
    field, (rgb, mask) = _core.windshield_gpu(
        device,
        np.ascontiguousarray(np.asarray(centers_px, np.float32).reshape(-1, 2)),
        np.ascontiguousarray(np.asarray(radii_px, np.float32).reshape(-1)),
        frame,
        compress=bool(compress),
        refraction=str(refraction),
        focal_px=float(focal_px),
        principal_px=pp,
        index=float(index),
        slope_px=float(slope_px),
        lookup_px=int(lookup_px),
    )
    return field, rgb, mask


def frame_glass(windshield: Windshield | str, seed: int) -> _core.Windshield | _core.GlassClock:
    """The glass a frame's request carries (``Weather(windshield=...)``): a :class:`Windshield`
    drawn as it stands, or a preset's :func:`clock`, drawn at the frame's ``time_s``."""
    if isinstance(windshield, Windshield):
        return windshield._core
    return clock(windshield, seed=seed)
