"""Issue 27, item 4: the A/B of one simulation step, before and after, on the same glass.

    python benches/windshield_27_step.py --save state.npz   # the "rain" preset on a 1024 x 1024 mm glass after 5 periods
    python benches/windshield_27_step.py --time state.npz   # median of 9 steps of 1/30 s from it, ms

Run --time with each build (PYTHONPATH at its package) on the one saved state, alternately.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from timing import median_s

from skyfall import windshield as ws

SIDE_MM = 1024.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--save", type=Path)
    ap.add_argument("--time", type=Path)
    args = ap.parse_args()
    if args.save:
        w = ws.Windshield(**dict(ws.PRESETS["rain"], glass_width_mm=SIDE_MM, glass_height_mm=SIDE_MM), seed=0)
        w.step(5 * w.params["wiper_period_s"])
        w.save(args.save)
        _, _, kind = w.drops()
        print(f"saved {len(kind)} drops ({int((kind == 2).sum())} particles) at t = {w.t_s:.2f} s")
    if args.time:
        def one() -> None:
            w = ws.Windshield.load(args.time)
            w.step(1.0 / 30.0)

        load = median_s(lambda: ws.Windshield.load(args.time), 9)
        t = median_s(one, 9) - load
        print(f"step of 1/30 s: {t * 1e3:.2f} ms (load {load * 1e3:.2f} ms subtracted)")


if __name__ == "__main__":
    main()
