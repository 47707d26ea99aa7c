"""The windshield presets' steady state, measured from long simulations (issue 31, item 2).

``simulate`` steps a preset's glass for many wiper periods and saves the state at the start of
each period from ``--keep-from`` on; ``table`` pools those states into the statistics that
``skyfall.windshield.steady`` draws a steady glass from
(``python/skyfall/data/windshield_steady_<preset>.npz``, ``skyfall.windshield.steady_table``).

    python benches/windshield_steady.py simulate --preset rain --seeds 1 3 4 --dir /tmp/steady
    python benches/windshield_steady.py table --preset rain --seeds 1 3 4 --dir /tmp/steady

    python benches/windshield_steady.py check --preset rain --seeds 2 --dir /tmp/steady \
        --out tests/data/windshield_steady_rain_s2.json

The seeds pooled into a table are listed in it; ``check`` compares 8 draws with the saved states
of a seed not among them, and writes the states' summary that ``tests/test_windshield_steady.py``
checks draws against.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from skyfall import windshield as ws



def simulate(preset: str, seed: int, periods: int, keep_from: int, out: Path) -> list[dict[str, float]]:
    """Steps ``preset`` for ``periods`` periods, saving the state at each period's end from
    ``keep_from`` on; the held water per period."""
    w = ws.preset(preset, seed=seed)
    period = ws._period_s(w)
    log = []
    t0 = time.perf_counter()
    for k in range(1, periods + 1):
        w.step(period)
        log.append({"period": k, "on_glass_g": w.water_kg()["on_glass"] * 1e3, "s": time.perf_counter() - t0})
        print(json.dumps(log[-1]), flush=True)
        if k >= keep_from:
            w.save(out / f"{preset}_s{seed}_p{k:03d}.npz")
    return log


RADIUS_EDGES_MM = np.array([0.0, 0.6, 0.8, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 20.0])
"""The base-radius bins the drop-size histograms are compared in, mm."""


def summary(w: ws.Windshield) -> dict[str, Any]:
    """What a draw is checked by: held water (g) in all and in the glass's top 250 mm, the
    number of drops of each kind, and the mesh drops' base-radius histogram."""
    xy, r, kind = w.drops()
    st = w.state()
    d, p = st["drops"], st["particles"]
    mass = np.concatenate([d[:, 2], p[:, 2]])
    mesh = kind == 0
    return {
        "held_g": float(mass.sum() * 1e3),
        "top_g": float(mass[xy[:, 1] < 250.0].sum() * 1e3),
        "mesh": int(mesh.sum()),
        "trail": int((kind == 1).sum()),
        "particles": int((kind == 2).sum()),
        "mesh_g": float(mass[mesh].sum() * 1e3),
        "radius_hist": np.histogram(r[mesh], RADIUS_EDGES_MM)[0].tolist(),
    }


def check(preset: str, states: list[Path], seeds: list[int]) -> dict[str, Any]:
    """Draws against saved states of a long simulation: each quantity's mean over the draws and
    over the states, and the states' range."""
    sims = [summary(ws.Windshield.load(f)) for f in states]
    t0 = time.perf_counter()
    draws = [summary(ws.steady(preset, seed=s)) for s in seeds]
    draw_s = (time.perf_counter() - t0) / len(seeds)
    out: dict[str, Any] = {"draw_s": draw_s, "states": len(states), "draws": len(seeds)}
    for k in sims[0]:
        a, b = np.array([x[k] for x in sims], float), np.array([x[k] for x in draws], float)
        out[k] = {"sim_mean": a.mean(0).tolist(), "sim_min": a.min(0).tolist(), "sim_max": a.max(0).tolist(), "draw_mean": b.mean(0).tolist()}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["simulate", "table", "check"])
    ap.add_argument("--preset", default="rain", choices=sorted(ws.PRESETS))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 3, 4])
    ap.add_argument("--periods", type=int, default=56)
    ap.add_argument("--keep-from", type=int, default=36)
    ap.add_argument("--dir", type=Path, default=Path("/tmp/steady"))
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    a.dir.mkdir(parents=True, exist_ok=True)
    if a.what == "simulate":
        for s in a.seeds:
            simulate(a.preset, s, a.periods, a.keep_from, a.dir)
        return
    if a.what == "check":
        states = sorted(f for s in a.seeds for f in a.dir.glob(f"{a.preset}_s{s}_p*.npz") if a.keep_from <= int(f.stem.split("_p")[-1]) <= a.periods)
        c = check(a.preset, states, list(range(100, 108)))
        print(json.dumps(c, indent=1))
        if a.out:
            ref: dict[str, Any] = {
                "source": f"python benches/windshield_steady.py check --preset {a.preset} --seeds {' '.join(map(str, a.seeds))}: "
                f"the {a.preset} preset's 1400 x 800 mm glass stepped from dry, its states at the start of periods {a.keep_from}-{a.periods} "
                f"({len(states)} states); sim_mean, sim_min, sim_max over them",
                "radius_edges_mm": RADIUS_EDGES_MM.tolist(),
            }
            ref.update({k: {q: v[q] for q in ("sim_mean", "sim_min", "sim_max")} for k, v in c.items() if isinstance(v, dict)})
            a.out.write_text(json.dumps(ref, indent=1))
        return
    states = sorted(f for s in a.seeds for f in a.dir.glob(f"{a.preset}_s{s}_p*.npz") if a.keep_from <= int(f.stem.split("_p")[-1]) <= a.periods)
    t = ws.steady_table([ws.Windshield.load(f) for f in states])
    t["sources"] = np.array(" ".join(sorted(p.name for p in states)))
    out = a.out or Path(ws.__file__).parent / "data" / f"windshield_steady_{a.preset}.npz"
    np.savez_compressed(out, **t)
    print(f"{out}: {len(states)} states, {out.stat().st_size / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
