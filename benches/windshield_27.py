"""Issue 27, item 4: the windshield's drops merging, sliding and the glass's steady state,
each measured on the simulation's output against a reference computed here (the glass's area,
Furmidge's critical size, the water that arrived), never from the simulation's own summaries.

    python benches/windshield_27.py --json out.json               # measure this build
    python benches/windshield_27.py --md before.json after.json   # the table (to stdout)

1. parked glass (preset "parked": 10 mm/h, no wipers, at rest, 1400 x 800 mm), 600 s: the
   drops' footprints pi a^2 summed over the glass's area; the share of drops whose footprint
   overlaps another's (centres closer than a_i + a_j, by a k-d tree); the held water's mean
   depth (on the glass / rho_w / area).
2. 14 m/s, no wipers (the "rain" preset's rain and speed, 0 wipers), 120 s: the water that
   left the glass across an edge, as a share of what arrived; the largest base radius against
   Furmidge's critical 3.47 mm.
3. the "rain" preset (two wipers, period 1.5 s, 14 m/s, 10 mm/h, 1400 x 800 mm): the water
   on the glass at the end of each wiper period, 1 to 40; periods 10 and 40 and their ratio.
4. one simulation step (1/30 s) of the "rain" preset after 10 periods, median of 9, on its
   1400 x 800 mm glass (what benches/bench_windshield.py draws at 1024^2) and on a
   1024 x 1024 mm glass.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from timing import median_s

from skyfall import windshield as ws

RHO_W = 998.2  # kg/m^3, the simulation's water at 20 degC
PERIODS = 60  # the table shows 10 and 40, and the mean of 41-60 where measured
GLASS: dict[str, float] = {}  # glass_width_mm / glass_height_mm over the presets' (--glass)


def overlap_share(xy: np.ndarray, a: np.ndarray) -> float:
    """The share of drops whose footprint (a disc of its base radius) overlaps another's.
    A pair overlaps when its centres are closer than a_i + a_j <= 2 max(a_i, a_j): each pair
    is found from its larger drop's ball of radius 2 a."""
    n = len(a)
    if n < 2:
        return 0.0
    tree = cKDTree(xy)
    hit = np.zeros(n, bool)
    for i, near in enumerate(tree.query_ball_point(xy, r=2.0 * a)):
        for j in near:
            if j != i and a[j] <= a[i] and math.dist(xy[i], xy[j]) < a[i] + a[j]:
                hit[i] = hit[j] = True
    return float(hit.mean())


def parked() -> dict[str, float]:
    w = ws.Windshield(**dict(ws.PRESETS["parked"], **GLASS), seed=0)
    t0 = time.perf_counter()
    for _ in range(60):
        w.step(10.0)
    wall = time.perf_counter() - t0
    xy, a, kind = w.drops()
    area = w.params["glass_width_mm"] * w.params["glass_height_mm"]
    mesh = kind == 0
    water = w.water_kg()
    return {
        "drops": int(mesh.sum()),
        "trail_drops": int((kind == 1).sum()),
        "footprint_over_area": float(np.sum(np.pi * a[mesh] ** 2) / area),
        "footprint_over_area_with_trails": float(np.sum(np.pi * a**2) / area),
        "overlap_share": overlap_share(xy[mesh], a[mesh]),
        "depth_mm": water["on_glass"] / RHO_W / (area * 1e-6) * 1e3,
        "arrived_depth_mm": water["arrived"] / RHO_W / (area * 1e-6) * 1e3,
        "left_share": water["swept_off"] / water["arrived"],
        "max_base_radius_mm": float(a.max()),
        "wall_s": wall,
    }


def speed14() -> dict[str, float]:
    p = dict(ws.PRESETS["rain"], wipers=0, **GLASS)
    w = ws.Windshield(**p, seed=0)
    out: dict[str, float] = {}
    first = None
    for k in range(1, 121):
        w.step(1.0)
        if first is None and w.water_kg()["swept_off"] > 0.0:
            first = float(k)
    water = w.water_kg()
    _, a, kind = w.drops()
    a_c, _ = ws.furmidge_critical(40.0, 20.0, 30.0)
    out["arrived_kg"] = water["arrived"]
    out["left_kg"] = water["swept_off"]
    out["left_share"] = water["swept_off"] / water["arrived"]
    out["first_leaves_s"] = first if first is not None else float("nan")
    out["max_base_radius_mm"] = float(a[kind == 0].max())
    out["critical_mm"] = a_c * 1e3
    return out


def rain_periods() -> dict[str, object]:
    w = ws.Windshield(**dict(ws.PRESETS["rain"], **GLASS), seed=0)
    period = w.params["wiper_period_s"]
    held = []
    t0 = time.perf_counter()
    for k in range(PERIODS):
        w.step(period)
        held.append(w.water_kg()["on_glass"])
        print(f"  period {k + 1}: {held[-1] * 1e3:.2f} g", file=sys.stderr, flush=True)
    wall = time.perf_counter() - t0
    water = w.water_kg()
    arrival = w.arrival_kg_per_s()
    return {
        "held_kg": held,
        "held_10_kg": held[9],
        "held_40_kg": held[39],
        "ratio_40_10": held[39] / held[9],
        "held_mean_41_60_kg": float(np.mean(held[40:60])) if len(held) >= 60 else None,
        "held_min_41_60_kg": float(np.min(held[40:60])) if len(held) >= 60 else None,
        "held_max_41_60_kg": float(np.max(held[40:60])) if len(held) >= 60 else None,
        "arrival_kg_per_period": arrival * period,
        "periods": len(held),
        "balance_error": abs(water["on_glass"] + water["swept_off"] + water["evaporated"] - water["arrived"]) / water["arrived"],
        "wall_s_40_periods": wall,
    }


def step_time(width_mm: float, height_mm: float) -> dict[str, float]:
    p = dict(ws.PRESETS["rain"], glass_width_mm=width_mm, glass_height_mm=height_mm)
    w = ws.Windshield(**p, seed=0)
    w.step(10 * p["wiper_period_s"])
    n = len(w.drops()[0])
    return {"drops": n, "step_s": median_s(lambda: w.step(1.0 / 30.0), 9)}


def measure(path: Path | None, sections: list[str]) -> dict[str, object]:
    """Measures ``sections`` in turn, rewriting ``path`` after each."""
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=Path(__file__).parent).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True, cwd=Path(__file__).parent).stdout.strip()
    out: dict[str, object] = {
        "env": {"rev": rev + ("+" if dirty else ""), "cpus": os.cpu_count(), "machine": platform.machine(), "date": time.strftime("%Y-%m-%d %H:%M"), "glass": GLASS or "the presets'"},
    }
    for k in sections:
        out[k] = progress(k, SECTIONS[k])
        if path is not None:
            path.write_text(json.dumps(out, indent=2))
    return out


SECTIONS = {
    "parked": parked,
    "speed14": speed14,
    "rain": rain_periods,
    "step_1400x800": lambda: step_time(1400.0, 800.0),
    "step_1024x1024": lambda: step_time(1024.0, 1024.0),
}


def progress(name: str, f: object) -> object:
    t0 = time.perf_counter()
    out = f()  # type: ignore[operator]
    print(f"{name}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return out


ROWS = [
    ("parked, 600 s", "footprints / glass area (mesh drops)", "parked", "footprint_over_area", "{:.3f}"),
    ("parked, 600 s", "footprints / glass area (with trail drops)", "parked", "footprint_over_area_with_trails", "{:.3f}"),
    ("parked, 600 s", "share of drops overlapping a neighbour", "parked", "overlap_share", "{:.3f}"),
    ("parked, 600 s", "held water, mean depth mm", "parked", "depth_mm", "{:.3f}"),
    ("parked, 600 s", "arrived water, depth mm (reference)", "parked", "arrived_depth_mm", "{:.3f}"),
    ("parked, 600 s", "left the glass / arrived", "parked", "left_share", "{:.3f}"),
    ("parked, 600 s", "largest base radius, mm", "parked", "max_base_radius_mm", "{:.2f}"),
    ("parked, 600 s", "mesh drops", "parked", "drops", "{:d}"),
    ("14 m/s, no wipers, 120 s", "left the glass, kg", "speed14", "left_kg", "{:.4f}"),
    ("14 m/s, no wipers, 120 s", "left the glass / arrived", "speed14", "left_share", "{:.3f}"),
    ("14 m/s, no wipers, 120 s", "first water leaves after, s", "speed14", "first_leaves_s", "{:.0f}"),
    ("14 m/s, no wipers, 120 s", "largest base radius, mm (Furmidge: 3.47)", "speed14", "max_base_radius_mm", "{:.2f}"),
    ("rain preset", "held water after 10 periods, g", "rain", "held_10_kg", "g"),
    ("rain preset", "held water after 40 periods, g", "rain", "held_40_kg", "g"),
    ("rain preset", "held 40 / held 10", "rain", "ratio_40_10", "{:.3f}"),
    ("rain preset", "held water, mean of periods 41-60, g", "rain", "held_mean_41_60_kg", "g"),
    ("rain preset", "held water, least of periods 41-60, g", "rain", "held_min_41_60_kg", "g"),
    ("rain preset", "held water, most of periods 41-60, g", "rain", "held_max_41_60_kg", "g"),
    ("rain preset", "arrival per period, g (reference)", "rain", "arrival_kg_per_period", "g"),
    ("rain preset", "|mass balance error| / arrived, at the end", "rain", "balance_error", "{:.1e}"),
    ("step, rain preset 1400 x 800 mm", "drops after 10 periods", "step_1400x800", "drops", "{:d}"),
    ("step, rain preset 1400 x 800 mm", "one step of 1/30 s, ms", "step_1400x800", "step_s", "ms"),
    ("step, rain preset 1024 x 1024 mm", "drops after 10 periods", "step_1024x1024", "drops", "{:d}"),
    ("step, rain preset 1024 x 1024 mm", "one step of 1/30 s, ms", "step_1024x1024", "step_s", "ms"),
]


def fmt(v: object, f: str) -> str:
    if v is None:
        return "-"
    if f == "g":
        return f"{float(v) * 1e3:.1f}"  # type: ignore[arg-type]
    if f == "ms":
        return f"{float(v) * 1e3:.2f}"  # type: ignore[arg-type]
    return f.format(v)


def table(before: dict, after: dict) -> str:
    lines = ["| case | quantity | before | after |", "|---|---|---|---|"]
    for case, what, group, key, f in ROWS:
        lines.append(f"| {case} | {what} | {fmt(before.get(group, {}).get(key), f)} | {fmt(after.get(group, {}).get(key), f)} |")
    lines.append("")
    lines.append("Held water (g) at the end of wiper periods 1-40, rain preset:")
    lines.append("")
    ks = (1, 2, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60)
    lines.append("| periods | " + " | ".join(str(k) for k in ks) + " |")
    lines.append("|---|" + "---|" * len(ks))
    for name, d in (("before", before), ("after", after)):
        held = d.get("rain", {}).get("held_kg", [])
        lines.append(f"| {name} | " + " | ".join(f"{held[k - 1] * 1e3:.1f}" if k <= len(held) else "-" for k in ks) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", type=Path)
    ap.add_argument("--md", nargs=2, type=Path)
    ap.add_argument("--glass", nargs=2, type=float, metavar=("WIDTH_MM", "HEIGHT_MM"), help="a glass other than the presets' 1400 x 800 mm")
    ap.add_argument("--sections", default=",".join(SECTIONS), help=f"comma-separated, of {','.join(SECTIONS)}")
    args = ap.parse_args()
    if args.glass:
        GLASS.update(glass_width_mm=args.glass[0], glass_height_mm=args.glass[1])
    if args.md:
        before, after = (json.loads(p.read_text()) for p in args.md)
        print(table(before, after))
        return
    out = measure(args.json, args.sections.split(","))
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    sys.exit(main())
