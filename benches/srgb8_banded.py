"""The 8-bit output of frames the fused path does not draw (clouds, a snow cover, box scenes,
layers other than the particles' alphas): ``render_srgb8``, which draws the stages band by band
and encodes each band as it is finished (``frame/encoded.rs``), against the float frame encoded
in Python (``render`` + ``io.to_srgb8``, what ``render_srgb8`` did for these frames before), at
1920x1080 on the CPU, the two timed alternately in one run. Both give the same bytes (tested in
tests/test_render_srgb8.py).

Writes benches/results/srgb8_banded.md and .json. Run with ``make bench``.
"""

from __future__ import annotations

import json
import platform
from pathlib import Path

import numpy as np

from timing import block_times_s

from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes

RESULTS = Path(__file__).parent / "results"


def main() -> None:
    r = Renderer(1920, 1080, backend="cpu")
    rng = np.random.default_rng(0)
    img = rng.integers(0, 256, (1080, 1920, 3), dtype=np.uint8)
    depth = np.full((1080, 1920), 30.0, np.float32)
    depth[:300] = np.inf
    photo = PhotoScene(img, depth, camera=Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0))
    kw = dict(seed=1, ambient_spacing_m=4.0)
    cases = {
        "street box scene, 20 mm/h rain, visibility 500 m": (scenes.street(), Weather(rain_rate_mm_h=20.0, visibility_m=500.0), None),
        "photo, broken clouds, 5 mm/h rain": (photo, Weather(clouds="broken", sun_elevation_deg=30.0, sun_azimuth_deg=180.0, rain_rate_mm_h=5.0), None),
        "photo, 20 mm/h rain, with the transmittance layer": (photo, Weather(rain_rate_mm_h=20.0, visibility_m=300.0), ("transmittance",)),
    }
    rows = []
    for name, (scene, weather, layers) in cases.items():
        fns = {
            "banded": lambda s=scene, w=weather, l=layers: r.render_srgb8(s, w, layers=l, **kw),
            "float + encode": lambda s=scene, w=weather, l=layers: io.to_srgb8(r.render(s, w, layers=l, **kw).rgb),
        }
        for f in fns.values():
            f()
        times = block_times_s(fns, blocks=9, per_block=2)
        med = {k: float(np.median(v)) for k, v in times.items()}
        rows.append({"case": name, "banded_ms": 1e3 * med["banded"], "float_encode_ms": 1e3 * med["float + encode"],
                     "speedup": med["float + encode"] / med["banded"]})
        print(rows[-1])
    lines = [
        "# The banded 8-bit output against the float frame encoded",
        "",
        f"1920x1080, CPU, {platform.processor() or platform.machine()}; medians of 9 alternating blocks of 2 calls "
        "(benches/srgb8_banded.py). The same bytes either way; the banded path holds no frame-sized float buffer "
        "(a 1080p float RGB frame and its depth are 33 MB).",
        "",
        "| frame | render_srgb8 (banded), ms | render + io.to_srgb8, ms | speed-up |",
        "|---|---|---|---|",
        *(f"| {x['case']} | {x['banded_ms']:.1f} | {x['float_encode_ms']:.1f} | {x['speedup']:.2f}x |" for x in rows),
        "",
    ]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "srgb8_banded.md").write_text("\n".join(lines))
    (RESULTS / "srgb8_banded.json").write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
