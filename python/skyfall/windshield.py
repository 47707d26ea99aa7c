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

A dataset item at t = 60 s need not step 60 s of rain: :func:`warm` steps ``warm_up_periods`` periods once per (preset, seed), keeps the state
(:meth:`Windshield.state`, in memory here or saved with :meth:`Windshield.save`) and steps
from it only the item's phase within a period: ``t mod T`` of work at most, per item. By then
the glass is statistically stationary: the water it holds goes up and down around a steady
level, what leaves matching what arrives (see :func:`warm`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import in_range, integer, real, values

__all__ = [
    "PRESETS",
    "SETTLED_PERIODS",
    "WARM_UP_PERIODS",
    "GlassView",
    "Windshield",
    "composite",
    "draw_gpu",
    "frame_stage",
    "furmidge_critical",
    "metaball_height_map",
    "normals",
    "preset",
    "refract",
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
"""The wiper periods :func:`warm` steps by default before its cached state: a glass still filling
(about 12 s of stepping for the ``rain`` preset on 2 cores)."""

SETTLED_PERIODS: Final = 40
"""The wiper periods after which the ``rain`` preset's glass has settled: its held water stays in
a steady band from there (``benches/results/windshield_27.md``); ``warm(...,
warm_up_periods=SETTLED_PERIODS)`` draws from that steady state, at minutes of stepping."""


@lru_cache(maxsize=16)
def _warm_state(name: str, seed: int, warm_up_periods: int) -> tuple[dict[str, Any], float]:
    w = preset(name, seed=seed)
    period = float(w.params.get("wiper_period_s", 1.5)) if w.params["wipers"] else 2.0
    for _ in range(warm_up_periods):
        w.step(period)
    return w.state(), period


def warm(name: str, t_s: float, *, seed: int = 0, warm_up_periods: int = WARM_UP_PERIODS) -> Windshield:
    """A preset's windshield as it is at ``t_s`` into steady rain, cheaply.

    The state after ``warm_up_periods`` wiper periods (2 s each without wipers) is computed
    once per (name, seed) and cached; from it only ``t_s mod period`` is stepped, so the
    wipers stand where they would at ``t_s`` and the drops are the glass after those periods
    (not the one exact history of ``t_s`` seconds of rain). The swept glass is clear after a
    sweep, but the glass the blades do not reach (half of the presets' glass) fills with drops
    until they grow past the size at which they slide (Furmidge's criterion with the airflow),
    which at the ``rain`` preset's 14 m/s takes some 30 periods, overshoots once and then
    settles: from :data:`SETTLED_PERIODS` (40) on, the held water stays within its steady band
    (``benches/results/windshield_27.md``). The default, :data:`WARM_UP_PERIODS` (4), is a
    glass still filling, chosen for its cost: the warm-up is paid once per (name, seed) and
    process, about 12 s for the ``rain`` preset on 2 cores, while 10 periods take about 77 s
    and 40 several minutes (the step's cost grows with the drops held). Pass
    ``warm_up_periods=SETTLED_PERIODS`` for a draw from the steady state. The ``drizzle``
    glass (a fifth of the rain) and the ``parked`` one (no wipers, 2 s "periods") fill more
    slowly and are not settled after 40 either (not measured).

    Parameters
    ----------
    name : str
        A preset, :data:`PRESETS`.
    t_s : float
        Time into the rain, s, in [-1e7, 1e7] (taken modulo the period).
    seed : int
        The windshield's seed.
    warm_up_periods : int
        Periods stepped once before the cache, in [1, 100] (default :data:`WARM_UP_PERIODS`);
        fewer than :data:`SETTLED_PERIODS` give a glass still filling.
    """
    integer("warm_up_periods", warm_up_periods, 1, 100)
    t = in_range("time_s", t_s)
    state, period = _warm_state(name, int(seed), int(warm_up_periods))
    w = preset(name, seed=seed)
    w = Windshield(**w.params, state={k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in state.items()})
    phase = math.fmod(t, period) % period
    if phase > 0.0:
        w.step(phase)
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


@dataclass(frozen=True)
class GlassView:
    """How the camera sees the glass: a plane ``distance_m`` in front of it, the glass's centre
    on the optical axis, its slope foreshortened by sin(tilt) (the camera looks horizontally).

    Parameters
    ----------
    focal_px : float
        The camera's focal length, px.
    width, height : int
        The frame, px.
    distance_m : float
        From the camera to the glass, m (default 0.8).
    blur_px : float
        The drops' blur circle, px (0: in focus).
    principal_px : (float, float), optional
        The principal point, px (default the frame's centre).
    """

    focal_px: float
    width: int
    height: int
    distance_m: float = 0.8
    blur_px: float = 0.0
    principal_px: tuple[float, float] | None = None

    @staticmethod
    def covering(windshield: Windshield, focal_px: float, width: int, height: int) -> float:
        """The distance, m, at which the glass just covers a ``width`` x ``height`` frame (a
        driver's view: the windshield fills it), at least 0.2 m."""
        p = windshield.params
        fore = math.sin(math.radians(max(p["glass_tilt_deg"], 1.0)))
        d_mm = min(p["glass_width_mm"] * focal_px / width, p["glass_height_mm"] * fore * focal_px / height)
        return max(float(d_mm) * 1e-3, 0.2)

    def px_per_mm(self) -> float:
        """Image px per glass mm across the glass."""
        return self.focal_px / (self.distance_m * 1e3)

    def to_px(self, windshield: Windshield, xy_mm: NDArray[np.float64]) -> NDArray[np.float32]:
        """Glass mm to image px (x, y)."""
        s = self.px_per_mm()
        p = windshield.params
        fore = math.sin(math.radians(max(p["glass_tilt_deg"], 1.0)))
        x = self.width / 2.0 + (xy_mm[:, 0] - p["glass_width_mm"] / 2.0) * s
        y = self.height / 2.0 + (xy_mm[:, 1] - p["glass_height_mm"] / 2.0) * s * fore
        return np.stack([x, y], axis=1).astype(np.float32)


def blur_circle_px(
    focal_length_mm: float, f_number: float, focus_distance_m: float, sensor_width_mm: float, width: int, distance_m: float
) -> float:
    """The thin lens's blur circle, px, of the glass at ``distance_m`` m when focused at
    ``focus_distance_m`` m (inf: at infinity): c = (f/N) · f/(s − f) · |z − s|/z on a sensor
    ``sensor_width_mm`` wide imaged on ``width`` px, f = ``focal_length_mm``."""
    f = focal_length_mm * 1e-3
    s = focus_distance_m
    if not math.isfinite(s):
        c_m = (f / f_number) * f / distance_m
    else:
        c_m = (f / f_number) * f / max(s - f, 1e-9) * abs(distance_m - s) / distance_m
    return float(c_m * 1e3 / sensor_width_mm * width)


def composite(
    frame_rgb: NDArray[np.float32],
    windshield: Windshield,
    view: GlassView,
    *,
    refraction: Literal["offset", "snell"] = "offset",
    blades: bool = True,
    device: Any = None,
) -> tuple[NDArray[np.float32], dict[str, NDArray[np.float32]]]:
    """``frame_rgb`` seen through ``windshield``'s drops as ``view`` places the glass, with
    the wipers' blades drawn over it (``blades``, :func:`draw_blades`); on a GPU ``device``
    (``Renderer(backend="gpu")``'s) the drops in focus are drawn by the GPU pass.

    Returns
    -------
    (ndarray of float32 (H, W, 3), dict)
        The frame and its layers ``drop_mask`` (the drops' coverage, 0-1) and ``drop_height``
        (the compressed metaball field above the 0.5 threshold, 0 off the drops).
    """
    centres_mm, radii_mm = windshield.metaballs()
    s = view.px_per_mm()
    centres = view.to_px(windshield, centres_mm) if len(centres_mm) else np.zeros((0, 2), np.float32)
    radii = (radii_mm * s).astype(np.float32)
    keep = radii > 0.05
    # a cap of the mean contact angle: edge slope tan(theta) for a drop of the typical 1.5 mm
    theta = math.radians(0.5 * (windshield.params["advancing_deg"] + windshield.params["receding_deg"]))
    slope = 1.5 * s * math.tan(min(theta, math.radians(80.0)))
    if device is not None and view.blur_px == 0.0:
        field, rgb, mask = draw_gpu(
            device, centres[keep], radii[keep], frame_rgb, focal_px=view.focal_px, slope_px=slope, refraction=refraction, principal_px=view.principal_px
        )
    else:
        field = metaball_height_map(centres[keep], radii[keep], (view.height, view.width))
        rgb, mask = refract(
            frame_rgb, field, focal_px=view.focal_px, slope_px=slope, refraction=refraction, blur_px=view.blur_px, principal_px=view.principal_px
        )
    height = np.maximum(field - np.float32(0.5), np.float32(0.0))
    if blades:
        draw_blades(rgb, windshield, view)
    return rgb, {"drop_mask": mask, "drop_height": height}


BLADE_ALBEDO: Final = 0.04
"""The blades' rubber and arm, relative to a white surface under the same sky."""


def draw_blades(rgb: NDArray[np.float32], windshield: Windshield, view: GlassView) -> None:
    """Draws the wipers' blades into ``rgb`` in place: dark (:data:`BLADE_ALBEDO`, in the
    frame's units: 1.0 is a white surface under the open sky), anti-aliased over one pixel across their edges, sharp (not defocused)."""
    p = windshield.params
    s = view.px_per_mm()
    fore = math.sin(math.radians(max(p["glass_tilt_deg"], 1.0)))
    h, w = rgb.shape[:2]
    for (px0, py0), angle, length, width in windshield.blades():
        ends = np.array([[px0, py0], [px0 + length * math.cos(angle), py0 - length * math.sin(angle)]])
        pe = view.to_px(windshield, ends)
        lo = np.floor(pe.min(axis=0) - width * s).astype(int)
        hi = np.ceil(pe.max(axis=0) + width * s).astype(int)
        x0, y0 = max(lo[0], 0), max(lo[1], 0)
        x1, y1 = min(hi[0], w), min(hi[1], h)
        if x0 >= x1 or y0 >= y1:
            continue
        yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64) + 0.5
        # back to glass mm, then along and across the blade
        gx = (xx - view.width / 2.0) / s + p["glass_width_mm"] / 2.0
        gy = (yy - view.height / 2.0) / (s * fore) + p["glass_height_mm"] / 2.0
        dx, dy = gx - px0, py0 - gy
        c, sn = math.cos(angle), math.sin(angle)
        along = dx * c + dy * sn
        across = -dx * sn + dy * c
        # one pixel of edge, measured in the blade's across direction on screen
        px_across = s * math.hypot(sn, c * fore)
        cover = np.clip((0.5 * width - np.abs(across)) * px_across + 0.5, 0.0, 1.0)
        cover *= np.clip((length - along) * s + 0.5, 0.0, 1.0) * (along >= 0.0)
        cover = cover.astype(np.float32)[..., None]
        region = rgb[y0:y1, x0:x1]
        region *= 1.0 - cover
        region += cover * np.float32(BLADE_ALBEDO)


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


def frame_stage(
    rgb: NDArray[np.float32], windshield: Windshield | str, camera: Any, *, time_s: float, seed: int, device: Any = None
) -> tuple[NDArray[np.float32], dict[str, NDArray[np.float32]]]:
    """The renderer's windshield stage: ``rgb`` seen through the glass of ``Weather(windshield=...)``.

    A preset's name is drawn by :func:`warm` at ``time_s`` and ``seed``; a :class:`Windshield`
    is used as it stands. The glass lies in front of ``camera`` (a :class:`skyfall.Camera` at
    the frame's resolution) where it just covers the frame (:meth:`GlassView.covering`); a thin-lens camera (``f_number``) focused beyond it blurs the
    drops by their blur circle (:func:`blur_circle_px`). On a GPU renderer's ``device`` the
    height map and the refraction run in the GPU pass (:func:`draw_gpu`) when the drops are in
    focus; defocused drops, and the blades, are drawn on the CPU.
    """
    w = windshield if isinstance(windshield, Windshield) else warm(windshield, time_s, seed=seed)
    fx, _fy, cx, cy = camera.intrinsics()
    distance_m = GlassView.covering(w, float(fx), int(camera.width), int(camera.height))
    blur = 0.0
    if getattr(camera, "f_number", None) is not None:
        f_mm = camera.focal_length_mm if camera.focal_length_mm is not None else fx * camera.sensor_width_mm / camera.width
        blur = min(blur_circle_px(f_mm, camera.f_number, camera.focus_distance_m, camera.sensor_width_mm, camera.width, distance_m), 1024.0)
    view = GlassView(focal_px=float(fx), width=int(camera.width), height=int(camera.height), distance_m=distance_m, blur_px=blur, principal_px=(float(cx), float(cy)))
    return composite(rgb, w, view, device=device)
