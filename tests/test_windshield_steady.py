"""The steady glass drawn statistically (issue 31, item 2): ``windshield.steady``.

Each draw is compared with long simulations of seeds its table did not pool: the held water,
where it lies, the number of drops of each kind and the mesh drops' size histogram; and it keeps
the simulation's own rules (no two mesh drops touching, one per cell), so stepping it on holds
the steady level instead of settling from somewhere else.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skyfall import windshield as ws

DATA = Path(__file__).parent / "data"
SMALL = dict(ws.PRESETS["rain"], glass_width_mm=250.0, glass_height_mm=150.0)
RADIUS_EDGES_MM = np.array([0.0, 0.6, 0.8, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 20.0])


def summary(w: ws.Windshield) -> dict[str, float | np.ndarray]:
    xy, r, kind = w.drops()
    st = w.state()
    mass = np.concatenate([st["drops"][:, 2], st["particles"][:, 2]])
    mesh = kind == 0
    top = xy[:, 1] < 0.3 * w.params["glass_height_mm"]
    return {
        "held_g": mass.sum() * 1e3,
        "top_g": mass[top].sum() * 1e3,
        "mesh": float(mesh.sum()),
        "particles": float((kind == 2).sum()),
        "radius_hist": np.histogram(r[mesh], RADIUS_EDGES_MM)[0].astype(float),
    }


def long_run(seed: int, periods: int = 60, keep_from: int = 31) -> list[ws.Windshield]:
    """The small glass of the rain preset stepped ``periods`` periods: its states from
    ``keep_from`` on, each at a period's start."""
    w = ws.Windshield(**SMALL, seed=seed)
    out = []
    for k in range(1, periods + 1):
        w.step(SMALL["wiper_period_s"])
        if k >= keep_from:
            out.append(ws.Windshield(**SMALL, seed=seed, state=w.state()))
    return out


def assert_no_mesh_drops_touch(w: ws.Windshield) -> None:
    xy, r, kind = w.drops()
    mesh = kind == 0
    p, a = xy[mesh], r[mesh]
    pairs = cKDTree(p).query_pairs(2.0 * a.max(), output_type="ndarray")
    d = np.hypot(*(p[pairs[:, 0]] - p[pairs[:, 1]]).T)
    assert not np.any(d < a[pairs[:, 0]] + a[pairs[:, 1]])
    cell = w.params["cell_mm"]
    cells = np.floor(xy[kind < 2] / cell).astype(np.int64)
    assert len(np.unique(cells, axis=0)) == len(cells)


@pytest.fixture(scope="module")
def small() -> tuple[dict, list[ws.Windshield]]:
    table = ws.steady_table(long_run(1) + long_run(3))
    return table, long_run(2) + long_run(4)


def test_a_drawn_glass_matches_a_long_simulation_the_table_did_not_pool(small) -> None:
    table, reference = small
    glass = ws.Windshield(**SMALL)
    sims = [summary(w) for w in reference]
    draws = [ws.steady(glass, seed=s, table=table) for s in range(100, 116)]
    for w in draws:
        assert_no_mesh_drops_touch(w)
    got = [summary(w) for w in draws]
    # The mean of 16 draws against the mean of two other seeds over 30 periods each: within
    # 10 % (held water, mesh drops), 12 % (the water in the top 30 % of the glass: a draw's
    # spread there is 15 %, the pooled seeds' mean 5 % below the others') and 20 %
    # (particles: the pooled seeds have 20 % fewer than seed 2), inside the range those
    # periods span.
    for k, rel in (("held_g", 0.1), ("top_g", 0.12), ("mesh", 0.1), ("particles", 0.2)):
        sim = np.array([s[k] for s in sims])
        mean = float(np.mean([g[k] for g in got]))
        assert mean == pytest.approx(sim.mean(), rel=rel), k
        assert sim.min() <= mean <= sim.max(), k
    sim_h = np.mean([s["radius_hist"] for s in sims], axis=0)
    got_h = np.mean([g["radius_hist"] for g in got], axis=0)
    big = sim_h >= 40
    assert big.sum() >= 5
    np.testing.assert_allclose(got_h[big], sim_h[big], rtol=0.2)
    # stepped on, it holds the steady level: each of 8 periods inside the simulation's range
    # (widened by 10 %), not settling from somewhere else
    held = np.array([s["held_g"] for s in sims])
    w = ws.steady(glass, seed=100, table=table)
    for _ in range(8):
        w.step(SMALL["wiper_period_s"])
        h = w.water_kg()["on_glass"] * 1e3
        assert 0.9 * held.min() <= h <= 1.1 * held.max()
    b = w.water_kg()
    assert b["on_glass"] + b["swept_off"] + b["evaporated"] == pytest.approx(b["arrived"], rel=1e-12)


@pytest.mark.parametrize("name", ws.STEADY_PRESETS)
def test_a_presets_draw_against_its_long_simulation(name: str) -> None:
    # tests/data/windshield_steady_<name>_s2.json: the states of the preset's 1400 x 800 mm
    # glass at seed 2 over the periods its table pools from seeds 1, 3 and 4 (36-56; drizzle
    # 120-160), by `python benches/windshield_steady.py check --preset <name> --seeds 2 ...`
    ref = json.loads((DATA / f"windshield_steady_{name}_s2.json").read_text())
    draws = [ws.steady(name, seed=s) for s in (5, 6, 7, 8)]
    got = [summary(w) for w in draws]
    for k in ("held_g", "mesh", "particles"):
        mean = float(np.mean([g[k] for g in got]))
        assert ref[k]["sim_min"] <= mean <= ref[k]["sim_max"], k
        # the rain preset's seeds 1-4 have their own means over periods 36-56 within 3 %
        assert mean == pytest.approx(ref[k]["sim_mean"], rel=0.07), k
    sim_h = np.array(ref["radius_hist"]["sim_mean"])
    got_h = np.mean([g["radius_hist"] for g in got], axis=0)
    big = sim_h >= 300
    np.testing.assert_allclose(got_h[big], sim_h[big], rtol=0.12)
    assert_no_mesh_drops_touch(draws[0])


def test_a_draw_is_the_same_bits_for_its_seed_and_another_for_another() -> None:
    a, b, c = ws.steady("rain", seed=7), ws.steady("rain", seed=7), ws.steady("rain", seed=8)
    sa, sb, sc = a.state(), b.state(), c.state()
    assert np.array_equal(sa["drops"], sb["drops"]) and np.array_equal(sa["particles"], sb["particles"])
    assert not np.array_equal(sa["drops"][:100], sc["drops"][:100])
    # 36 periods into the rain (the first state the table pooled), the wipers at the start of
    # their sweep, the water accounted
    assert a.t_s == pytest.approx(36 * 1.5)
    assert a.blades() == ws.preset("rain").blades()
    bal = a.water_kg()
    assert bal["arrived"] == pytest.approx(bal["on_glass"], rel=1e-12) and bal["swept_off"] == 0.0


def test_the_clock_starts_from_the_drawn_glass_and_steps_on_request() -> None:
    w = ws.warm("rain", 0.0, seed=9)
    d = ws.steady("rain", seed=9)
    assert np.array_equal(w.state()["drops"], d.state()["drops"])
    stepped = ws.warm("rain", 0.0, seed=9, warm_up_periods=1)
    assert stepped.t_s == pytest.approx(1.5)


def test_every_preset_has_a_table_measured_for_its_parameters_now() -> None:
    # a table whose preset's parameters changed since it was measured is left out (the preset
    # would step from dry glass): remake it with benches/windshield_steady.py
    assert ws.STEADY_PRESETS == tuple(ws.PRESETS)


def test_bad_requests_name_what_is_wrong() -> None:
    with pytest.raises(ValueError, match="no steady table|not a preset"):
        ws.steady("fog")
    with pytest.raises(ValueError, match="table=steady_table"):
        ws.steady(ws.Windshield(**SMALL))
    with pytest.raises(ValueError, match="seed"):
        ws.steady("rain", seed=-1)
    with pytest.raises(TypeError):
        ws.steady_table([])
    with pytest.raises(ValueError, match="same parameters"):
        ws.steady_table([ws.Windshield(**SMALL), ws.preset("rain")])
    # a table for another glass is refused by the core, naming the sizes
    table = ws.steady_table([ws.Windshield(**SMALL)])
    with pytest.raises(ValueError, match="squares"):
        ws.steady("rain", table=table)
