"""Frame benchmarks: the haze pass and the street scene at 1920x1080 on the CPU backend, on
the GPU backend (lavapipe here), and against numpy and the memory-bandwidth floor, all in
one run. Writes benches/results/render.md and render.json. Run with `make bench`.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path

import numpy as np
from timing import median_s

from skyfall import Camera, PhotoScene, Renderer, Weather, _core, scenes

RESULTS = Path(__file__).parent / "results"
W, H = 1920, 1080


def numpy_haze(img: np.ndarray, depth: np.ndarray, per_depth: np.ndarray, sigma: float, air: float) -> np.ndarray:
    t = np.exp(np.float32(-sigma) * depth * per_depth)
    return img * t[..., None] + np.float32(air) * (np.float32(1) - t[..., None])


def haze_photo() -> tuple[np.ndarray, np.ndarray, PhotoScene, Weather]:
    """The haze rows' W x H random float photo, its depths, the scene and the haze-only weather
    (shared with benches/ab.py)."""
    rng = np.random.default_rng(0)
    img = rng.uniform(0, 1, (H, W, 3)).astype(np.float32)
    depth = rng.uniform(1, 2000, (H, W)).astype(np.float32)
    cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=50.0)
    weather = Weather(rain_rate_mm_h=10.0, visibility_m=2000.0, rain_streaks=False)  # the haze alone
    return img, depth, PhotoScene(img, depth, camera=cam, encoding="linear"), weather


def main() -> None:
    img, depth, photo, weather = haze_photo()
    fx, fy, cx, cy = photo.camera.intrinsics()
    y, x = np.mgrid[0:H, 0:W].astype(np.float32) + np.float32(0.5)
    per_depth = np.sqrt(((x - cx) / fx) ** 2 + ((y - cy) / fy) ** 2 + 1).astype(np.float32)

    rows: list[dict[str, object]] = []
    dst = np.empty_like(img)
    floor = median_s(lambda: np.copyto(dst, img))
    rows.append({"what": "haze", "impl": "memory floor: one read+write of the RGB frame (numpy copyto)", "s": floor})
    cpu = Renderer(W, H, backend="cpu")
    rows.append({"what": "haze", "impl": "skyfall CPU backend (fused, rayon)", "s": median_s(lambda: cpu.render(photo, weather))})
    sigma = weather.extinction_per_m
    rows.append({"what": "haze", "impl": "numpy, same formula (precomputed ray lengths)", "s": median_s(lambda: numpy_haze(img, depth, per_depth, sigma, 3 / 7))})

    street = scenes.street()
    rows.append({"what": "street", "impl": "skyfall CPU backend: ray cast + haze", "s": median_s(lambda: cpu.render(street, weather))})

    gpu_info = None
    startup = first = None
    try:
        t0 = time.perf_counter()
        dev = _core.GpuDevice(require_hardware=False)
        startup = time.perf_counter() - t0
        gpu_info = dev.adapter_info
        gpu = Renderer(W, H, backend="gpu")
        t0 = time.perf_counter()
        gpu.render(photo, weather)
        first = time.perf_counter() - t0
        rows.append({"what": "haze", "impl": f"skyfall GPU backend ({gpu_info[0]}), incl. upload + readback", "s": median_s(lambda: gpu.render(photo, weather), 3)})
        rows.append({"what": "street", "impl": f"skyfall GPU backend ({gpu_info[0]}): ray cast + haze + readback", "s": median_s(lambda: gpu.render(street, weather), 3)})
    except _core.GpuUnavailableError as exc:
        gpu_info = (f"unavailable: {exc}", "", "", "")

    RESULTS.mkdir(parents=True, exist_ok=True)
    env = {"cpus": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(), "date": time.strftime("%Y-%m-%d")}
    (RESULTS / "render.json").write_text(
        json.dumps({"env": env, "frame": [W, H], "gpu": gpu_info, "gpu_startup_s": startup, "gpu_first_frame_s": first, "rows": rows}, indent=2)
    )
    lines = [
        "# Render benchmarks",
        "",
        f"{env['date']}, {env['cpus']} CPUs ({env['machine']}), {W}x{H} float32 frames, 10 mm/h rain + 2 km visibility haze.",
        "Medians of repeated runs in one process; written by `make bench`. Ratios are to the memory floor",
        "(one read+write pass over the RGB frame) measured in the same run.",
        "",
        "| pass | implementation | time | × memory floor |",
        "|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['what']} | {r['impl']} | {float(r['s']) * 1e3:.1f} ms | {float(r['s']) / floor:.1f} |")
    lines += [
        "",
        f"GPU adapter: {gpu_info[0] if gpu_info else '—'}.",
        f"Device start-up (instance, adapter, device, pipelines): {startup * 1e3:.0f} ms." if startup else "",
        f"First frame (includes llvmpipe's lazy shader compile): {first * 1e3:.0f} ms." if first else "",
    ]
    (RESULTS / "render.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
