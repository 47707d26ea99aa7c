"""A windshield preset's warm-up for a new seed (issue 31, item 2), A/B in fresh processes.

``python benches/windshield_warmup.py --base-python PATH`` runs each measurement in a fresh
process of this build and of the base's Python (a venv of an earlier commit, e.g. from
``benches/ab.py``), in turn, ``--rounds`` times, and writes ``benches/results/windshield_warmup.md``
and its section of ``benches/results/sweeps.md``. In each process: the street at 1024 x 1024 on
the CPU backend in 10 mm/h rain is rendered once without a windshield (the scene's maps made),
then with ``windshield="rain"`` at a seed never drawn before (``first``), then again at the same
seed and time (``seen``: the preset's clock cached), and one step of 1/30 s of that glass is
timed alone. The warm-up is first - seen.

``--later`` times this build alone at frame times in the epoch's later periods (the clock steps
each earlier period once, from the drawn glass) and writes
``benches/results/windshield_warmup_later.md``; the windshield section of ``sweeps.md`` is both
tables.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).parent / "results"

WORKER = r"""
import json, sys, time
from skyfall import Renderer, Weather, scenes
from skyfall import windshield as ws
t_s, seed = float(sys.argv[1]), int(sys.argv[2])
r = Renderer(1024, 1024, backend="cpu")
street = scenes.street()
r.render(street, Weather(rain_rate_mm_h=10.0), time_s=t_s, seed=seed)
weather = Weather(rain_rate_mm_h=10.0, windshield="rain")
t0 = time.perf_counter(); r.render(street, weather, time_s=t_s, seed=seed); first = time.perf_counter() - t0
t0 = time.perf_counter(); r.render(street, weather, time_s=t_s, seed=seed); seen = time.perf_counter() - t0
w = ws.warm("rain", t_s, seed=seed)
t0 = time.perf_counter(); w.step(1 / 30); step = time.perf_counter() - t0
print(json.dumps({"first": first, "seen": seen, "step": step, "held_g": w.water_kg()["on_glass"] * 1e3, "drops": len(w.drops()[1])}))
"""


def run(python: str, t_s: float, seed: int) -> dict[str, float]:
    out = subprocess.run([python, "-c", WORKER, str(t_s), str(seed)], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base-python")
    ap.add_argument("--later", action="store_true", help="this build alone, frames in the epoch's later periods")
    ap.add_argument("--base-label", default="base")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    if a.later:
        later(a.rounds)
        return
    if not a.base_python:
        ap.error("--base-python is needed (or --later)")
    rows: dict[tuple[str, float], list[dict[str, float]]] = {}
    for k in range(a.rounds):
        for t_s in (0.0, 0.9, 1.45):
            for label, py in (("base", a.base_python), ("head", sys.executable)):
                rows.setdefault((label, t_s), []).append(run(py, t_s, 1000 + k))
                print(label, t_s, rows[(label, t_s)][-1], flush=True)
    med = {key: {q: float(np.median([r[q] for r in v])) for q in v[0]} for key, v in rows.items()}
    lines = [
        "## The windshield's warm-up for a new seed (issue 31, item 2)",
        "",
        f"`benches/windshield_warmup.py`, {time.strftime('%Y-%m-%d')}, 2 CPUs (x86_64), CPU backend: the street at 1024 x 1024 in 10 mm/h rain through the `rain` preset's glass, "
        f"a new seed in a fresh process each, base ({a.base_label}: the glass stepped 4 wiper periods from dry) and head (the steady glass drawn, `windshield.steady`) in turn, "
        f"medians of {a.rounds} rounds. warm-up = the first frame of the seed - the same frame again (the clock cached); one step = 1/30 s of that glass.",
        "",
        "| frame time | version | first frame, s | seen frame, s | warm-up, s | one step, ms | warm-up / one step | drops on the glass | held water, g |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for t_s in (0.0, 0.9, 1.45):
        for label in ("base", "head"):
            m = med[(label, t_s)]
            wu = m["first"] - m["seen"]
            lines.append(
                f"| {t_s:g} s | {label} | {m['first']:.2f} | {m['seen']:.2f} | {wu:.2f} | {m['step'] * 1e3:.1f} | {wu / m['step']:.0f} | {m['drops']:.0f} | {m['held_g']:.1f} |"
            )
    text = "\n".join(lines) + "\n"
    (RESULTS / "windshield_warmup.md").write_text(text)
    (RESULTS / "windshield_warmup.json").write_text(json.dumps({f"{k[0]} {k[1]}": v for k, v in rows.items()}, indent=1))
    write_sweeps()
    print(text)


LATER_TIMES_S = (3.0, 5.0, 5.95)
"""Frame times in the `rain` preset's epoch (4 periods of 1.5 s) past its first period."""


def later(rounds: int) -> None:
    """This build alone at :data:`LATER_TIMES_S`, ``rounds`` new seeds each."""
    rows: dict[float, list[dict[str, float]]] = {}
    for k in range(rounds):
        for t_s in LATER_TIMES_S:
            rows.setdefault(t_s, []).append(run(sys.executable, t_s, 2000 + k))
            print(t_s, rows[t_s][-1], flush=True)
    lines = [
        "### Later in the epoch",
        "",
        f"The same measurement of this build alone ({time.strftime('%Y-%m-%d')}, `--later`, medians of {rounds} new seeds) at frame times past "
        "the epoch's first period: a frame in period k steps the glass through the k periods before it once (then keeps their "
        "starts), 90 steps of 1/60 s a period, from the drawn glass. What the drawn glass does not remove.",
        "",
        "| frame time | period of the epoch | first frame, s | seen frame, s | warm-up, s | one step, ms | warm-up / one step |",
        "|---|---|---|---|---|---|---|",
    ]
    for t_s, v in rows.items():
        m = {q: float(np.median([r[q] for r in v])) for q in v[0]}
        wu = m["first"] - m["seen"]
        lines.append(f"| {t_s:g} s | {int(t_s // 1.5)} | {m['first']:.2f} | {m['seen']:.2f} | {wu:.2f} | {m['step'] * 1e3:.1f} | {wu / m['step']:.0f} |")
    text = "\n".join(lines) + "\n"
    (RESULTS / "windshield_warmup_later.md").write_text(text)
    write_sweeps()
    print(text)


def write_sweeps() -> None:
    """sweeps.md's windshield section: windshield_warmup.md, then windshield_warmup_later.md."""
    parts = [RESULTS / "windshield_warmup.md", RESULTS / "windshield_warmup_later.md"]
    text = "\n".join(p.read_text() for p in parts if p.exists())
    sweeps = RESULTS / "sweeps.md"
    s = sweeps.read_text()
    head = s.split("## The windshield's warm-up")[0].rstrip("\n")
    sweeps.write_text(head + "\n\n" + text)


if __name__ == "__main__":
    main()
