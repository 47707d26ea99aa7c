"""The rain's far level of detail (``Weather.rain_far_m``) against the per-drop reference, for
benches/bench_rain.py: its error (mean opacity and the 8-px-blurred SSIM of the rain's coverage,
over seeds) next to its speed, on the bench's 1080p street photo, for a few rains and views.

Run on its own (``python benches/rain_far.py``) it prints the section it adds to rain.md.
"""

from __future__ import annotations

import copy
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.ndimage import gaussian_filter
from skimage.metrics import structural_similarity

from timing import median_s

from skyfall import Camera, PhotoScene, Renderer, Weather

SEEDS = 8
"""Seeds per case: mean opacity and SSIM are averaged over them."""

CASES: list[dict[str, Any]] = [
    {"case": "10 mm/h, 5 m region (the bench's frame)", "rate": 10.0, "near": 5.0, "far": 2.0},
    {"case": "10 mm/h, 5 m region, rain_method='billboards' (within 2 m drawn drop by drop all the same)", "rate": 10.0, "near": 5.0, "far": 2.0, "near_method": "billboards"},
    {"case": "10 mm/h, 5 m region, wind 6 m/s across", "rate": 10.0, "near": 5.0, "far": 2.0, "wind": (6.0, 0.0, 0.0)},
    {"case": "10 mm/h, 5 m region, camera moving 10 m/s forward", "rate": 10.0, "near": 5.0, "far": 2.0, "velocity": (0.0, 0.0, -10.0)},
    {"case": "25 mm/h, 10 m region", "rate": 25.0, "near": 10.0, "far": 3.0},
    {"case": "50 mm/h, 10 m region", "rate": 50.0, "near": 10.0, "far": 3.0},
]


def _ssim(a: np.ndarray, b: np.ndarray) -> float:
    """SSIM of two coverage layers over their own range (as bench_rain's billboard table)."""
    return float(structural_similarity(a, b, data_range=float(max(a.max(), b.max())) or 1.0))


def far_lod(cpu: Renderer, photo8: np.ndarray, depth: np.ndarray, camera: Camera) -> list[dict[str, Any]]:
    """Per case: the fused 8-bit frame's time per drop (the reference), with billboards and with
    the far level of detail, and the level of detail's error against the reference over
    ``SEEDS`` seeds."""
    h, w = depth.shape
    out: list[dict[str, Any]] = []
    for ci, case in enumerate(CASES):
        cam = copy.copy(camera)
        if "velocity" in case:
            cam.velocity_m_s = np.asarray(case["velocity"], np.float64)
        scene = PhotoScene(photo8, depth, camera=cam)
        base = {"rain_rate_mm_h": case["rate"], "rain_near_m": case["near"], "wind_m_s": case.get("wind", (0.0, 0.0, 0.0))}
        ref = Weather(**base, rain_method="drops")
        lod = Weather(**base, rain_method=case.get("near_method", "drops"), rain_far_m=case["far"])
        bill = Weather(**base)

        def layer(weather: Weather, seed: int) -> np.ndarray:
            alpha = np.empty((h, w), np.float32)
            cpu.render_srgb8(scene, weather, seed=seed, layers={"rain_alpha": alpha})
            return alpha.astype(np.float64)

        def timed(weather: Weather) -> Callable[[], object]:
            return lambda: cpu.render_srgb8(scene, weather)

        refs = [layer(ref, s) for s in range(SEEDS)]
        lods = [layer(lod, s) for s in range(SEEDS)]
        others = [layer(ref, 100 + s) for s in range(SEEDS)]
        ref_means = np.array([r.mean() for r in refs])
        lod_means = np.array([x.mean() for x in lods])
        blur = [gaussian_filter(x, 8) for x in refs], [gaussian_filter(x, 8) for x in lods], [gaussian_filter(x, 8) for x in others]
        # A frame whose textures are not cached yet (each call a new exposure: a new set), less
        # the cached frame's time: what making the shells' textures costs.
        def fresh(k: int) -> float:
            cam_k = copy.copy(cam)
            cam_k.exposure_s = cam.exposure_s * (1.0 + 1e-6 * (10 * ci + k + 1))
            scene_k = PhotoScene(photo8, depth, camera=cam_k)
            t0 = time.perf_counter()
            cpu.render_srgb8(scene_k, lod)
            return time.perf_counter() - t0

        t_fresh = statistics.median(fresh(k) for k in range(3))
        out.append(
            {
                **case,
                "textures_s": t_fresh - median_s(timed(lod), 5),
                "drops_s": median_s(timed(ref), 5),
                "billboards_s": median_s(timed(bill), 5),
                "far_s": median_s(timed(lod), 5),
                "ref_alpha": float(ref_means.mean()),
                "far_alpha": float(lod_means.mean()),
                # the ratio's standard error from the seed-to-seed spread of both
                "bias_se": float(
                    lod_means.mean() / ref_means.mean() * np.sqrt((lod_means.var(ddof=1) / lod_means.mean() ** 2 + ref_means.var(ddof=1) / ref_means.mean() ** 2) / SEEDS)
                ),
                "ssim_blur8": float(np.mean([_ssim(r, x) for r, x in zip(blur[0], blur[1])])),
                "ssim_blur8_seeds": float(np.mean([_ssim(r, x) for r, x in zip(blur[0], blur[2])])),
            }
        )
    return out


def far_lines(rows: list[dict[str, Any]]) -> list[str]:
    """rain.md's section on the far level of detail."""
    lines = [
        "",
        "## The far level of detail (`Weather.rain_far_m`) against the per-drop reference",
        "",
        "The 1920x1080 street photo, fused 8-bit path; per-drop streaks (billboards where the case says so) within `rain_far_m` of the camera",
        "(horizontally), the rest of the region as one pre-rasterised, world-anchored cylindrical layer per",
        "1.5 m (`skyfall-core/src/rain/far.rs`). Error against the per-drop reference (`rain_method=\"drops\"`,",
        f"no far level) over {SEEDS} seeds: the mean of `rain_alpha` (± one standard error of the ratio), and",
        "the SSIM of `rain_alpha` blurred to 8 px (Gaussian σ = 8 px), beside the reference against itself",
        f"at {SEEDS} other seeds (what two independent draws of the same rain score). Times: medians of 5",
        "frames, one seed, haze included; the layers' textures are made on a frame's first call and",
        "cached (not in these times: `textures` is what a frame whose textures are not cached yet",
        "takes more, the median of 3; they depend on the rain rate, the diameters, the exposure and",
        "the camera's focal length in pixels, not on the seed).",
        "",
        "| case | rain_far_m | per drop | billboards | far LOD | speed-up vs per drop | textures | mean opacity, LOD / reference | SSIM blur 8 px | reference vs itself |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['far']:g} m | {r['drops_s'] * 1e3:.1f} ms | {r['billboards_s'] * 1e3:.1f} ms | "
            f"{r['far_s'] * 1e3:.1f} ms | {r['drops_s'] / r['far_s']:.2f}x | +{r['textures_s'] * 1e3:.0f} ms | {r['far_alpha'] / r['ref_alpha']:.3f} ± {r['bias_se']:.3f} | "
            f"{r['ssim_blur8']:.3f} | {r['ssim_blur8_seeds']:.3f} |"
        )
    return lines


if __name__ == "__main__":
    from bench_rain import H, W, street_photo

    cpu = Renderer(W, H, backend="cpu")
    p = street_photo(cpu)
    print("\n".join(far_lines(far_lod(cpu, p.photo8, p.depth, p.camera))))  # type: ignore[arg-type]
