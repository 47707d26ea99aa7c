"""The wet stage's cost (``Weather.rain_duration_s``): 1920x1080 frames on the CPU, dry against
wet, timed alternately in one run; the stage's share of the wet frame is (wet - dry) / wet.
Cases: the dusk street with its lamps and headlights in 5 mm/h rain (the demo's wet frame), the
street by day, and the street as an 8-bit photo with its depth (the photo path's march through
the depth map) through ``render_srgb8``.

Writes benches/results/wet.md and .json. Run with ``make bench``.
"""

from __future__ import annotations

import json
import platform
from pathlib import Path

import numpy as np

from timing import block_times_s

from skyfall import Renderer, Weather, scenes
from skyfall._demo.photo import street_photo

RESULTS = Path(__file__).parent / "results"


def main() -> None:
    r = Renderer(1920, 1080, backend="cpu")
    kw = dict(seed=1, ambient_spacing_m=4.0)
    photo = street_photo(1920)
    dusk = dict(rain_rate_mm_h=5.0, sky_illuminance_lux=30.0)
    cases = {
        "dusk street, lamps and headlights, 5 mm/h (render)": (scenes.street(lamps=True, headlights=True), dusk, r.render),
        "street by day, 5 mm/h (render)": (scenes.street(), dict(rain_rate_mm_h=5.0), r.render),
        "street photo with depth, 5 mm/h (render_srgb8)": (photo, dict(rain_rate_mm_h=5.0), r.render_srgb8),
    }
    rows = []
    for name, (scene, weather, call) in cases.items():
        fns = {
            "dry": lambda s=scene, w=weather, c=call: c(s, Weather(**w), **kw),
            "wet": lambda s=scene, w=weather, c=call: c(s, Weather(**w, rain_duration_s=None), **kw),
        }
        times = block_times_s(fns, blocks=5, per_block=3)
        med = {k: float(np.median(v)) for k, v in times.items()}
        ratios = [w / d for w, d in zip(times["wet"], times["dry"])]
        rows.append({"case": name, "dry_ms": 1e3 * med["dry"], "wet_ms": 1e3 * med["wet"],
                     "wet_over_dry": float(np.median(ratios)), "stage_share": 1.0 - med["dry"] / med["wet"]})
        print(rows[-1])
    lines = [
        "# The wet stage's cost",
        "",
        f"1920x1080, CPU backend, {platform.processor() or platform.machine()}, {len(__import__('os').sched_getaffinity(0))} cores; "
        "medians of 5 alternating blocks of 3 calls (benches/wet.py). The stage's share is (wet - dry) / wet. "
        "The box scenes' wet stage casts each surface pixel's ray again, its three shelter rays, its mirror ray (lit with "
        "the lights' shadow rays) and its highlights' shadow rays; the photo's marches 64 steps through the depth map per "
        "surface pixel, and its dry frame takes the fused 8-bit path where the wet one takes the banded path. Both "
        "look up the puddles' relief on level faces, draw the film's microfacet normal per pixel and average the film's "
        "image along each row (16 px each side at this size).",
        "",
        "| frame | dry, ms | wet, ms | wet / dry (median of the blocks' ratios) | the wet stage's share of the wet frame |",
        "|---|---|---|---|---|",
        *(f"| {x['case']} | {x['dry_ms']:.0f} | {x['wet_ms']:.0f} | {x['wet_over_dry']:.2f} | {x['stage_share']:.0%} |" for x in rows),
        "",
    ]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "wet.md").write_text("\n".join(lines))
    (RESULTS / "wet.json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
