"""Snowfall at 1920x1080: frame time against the number of flakes (1 000 to 1 000 000) on both
backends, and the same run's albumentations RandomSnow (pinned 2.0.8, bench-only) and imgaug
Snowflakes on the same uint8 image, one image at a time, in one process.

The flake counts are set through ``snow_near_m`` at a fixed 2 mm/h: the flakes in view go as
snow_near_m^3, so the radius for a target count N is r1 * (N / n1)^(1/3) from a first
measurement n1 at r1, corrected once by a second measurement; the table gives the flakes the
frame reports (``frame.stats["snow_flakes"]``, the flakes generated in the voxels that can
reach the view) and the streaks it drew.

Writes benches/results/snow.md and snow.json. Run with ``make bench``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import json
import platform
from pathlib import Path

import numpy as np

from timing import median_s

from skyfall import GpuUnavailableError, PhotoScene, Renderer, Weather, io, scenes

RESULTS = Path(__file__).parent / "results"
W, H = 1920, 1080
RATE_MM_H = 2.0
TARGETS = [1_000, 5_000, 10_000, 100_000, 1_000_000]


def near_for(cpu: Renderer, scene: PhotoScene, target: int) -> tuple[float, dict[str, int]]:
    """The snow_near_m whose frame holds about ``target`` flakes (two measurements, cube root)."""
    r = 4.0
    for _ in range(3):
        stats = cpu.render(scene, Weather(snow_rate_mm_h=RATE_MM_H, snow_near_m=r)).stats
        n = max(stats["snow_flakes"], 1)
        r = float(min(50.0, max(0.05, r * (target / n) ** (1.0 / 3.0))))
    stats = cpu.render(scene, Weather(snow_rate_mm_h=RATE_MM_H, snow_near_m=r)).stats
    return r, stats


def main() -> None:
    cpu = Renderer(W, H, backend="cpu")
    street = scenes.street()
    clear = cpu.render(street)
    photo8 = io.to_srgb8(clear.rgb)
    scene = PhotoScene(photo8, clear.depth_m, camera=street.camera)
    try:
        gpu: Renderer | None = Renderer(W, H, backend="gpu")
        info = gpu.adapter_info or {}
        gpu_name = f"{info.get('name', '?')} ({info.get('device_type', '?')})"
    except GpuUnavailableError as exc:
        gpu, gpu_name = None, f"unavailable: {exc}"
    out8 = np.empty_like(photo8)
    rows = []
    for target in TARGETS:
        near, stats = near_for(cpu, scene, target)
        weather = Weather(snow_rate_mm_h=RATE_MM_H, snow_near_m=near)
        big = stats["snow_flakes"] > 200_000
        t_cpu8 = median_s(lambda: cpu.render_srgb8(scene, weather, out=out8), repeat=2 if big else 5)
        t_cpu = median_s(lambda: cpu.render(scene, weather), repeat=2 if big else 5)
        t_gpu: float | str
        if gpu is None:
            t_gpu = "-"
        else:
            try:
                t_gpu = median_s(lambda: gpu.render(scene, weather), repeat=1 if big else 3)
            except ValueError as exc:  # a device buffer limit, named
                t_gpu = f"refused: {exc}"
        rows.append({"target": target, "snow_near_m": near, **stats, "cpu_srgb8_s": t_cpu8, "cpu_float_s": t_cpu, "gpu_float_s": t_gpu})
        print(rows[-1], flush=True)

    import albumentations as A

    peers = []
    for name, aug in [
        ("albumentations 2.0.8 RandomSnow (bleach: brightens bright pixels, no flakes)", A.RandomSnow(method="bleach", p=1.0)),
        ("albumentations 2.0.8 RandomSnow (texture: a noise texture, no flakes)", A.RandomSnow(method="texture", p=1.0)),
    ]:
        peers.append({"impl": name, "s": median_s(lambda: aug(image=photo8)["image"], repeat=7)})
    try:
        import imgaug.augmenters as iaa

        snowflakes = iaa.Snowflakes(flake_size=(0.2, 0.7), speed=(0.007, 0.03))
        peers.append({"impl": "imgaug Snowflakes", "s": median_s(lambda: snowflakes(image=photo8), repeat=3)})
        imgaug_note = ""
    except ModuleNotFoundError:
        imgaug_note = (
            f"imgaug Snowflakes not measured: imgaug 0.4.0 (its last release) installs beside numpy {np.__version__} but its "
            "import fails (AttributeError: `np.sctypes` was removed in the NumPy 2.0 release), so requirements-bench.txt "
            "does not pin it and the venv does not hold it."
        )
    except Exception as exc:  # installed by hand, and broken by numpy 2
        imgaug_note = f"imgaug Snowflakes not measured: its import fails with numpy {np.__version__} ({type(exc).__name__}: {exc})."
    print(peers, imgaug_note, flush=True)

    env = {"python": platform.python_version(), "machine": platform.machine(), "cpus": os.cpu_count(), "gpu": gpu_name}
    (RESULTS / "snow.json").write_text(json.dumps({"env": env, "frame": [W, H], "rate_mm_h": RATE_MM_H, "rows": rows, "peers": peers, "imgaug": imgaug_note}, indent=2))
    alb = min(p["s"] for p in peers if p["impl"].startswith("albumentations"))
    fmt = lambda t: f"{t * 1e3:.0f} ms" if isinstance(t, float) else t  # noqa: E731
    lines = [
        "# Snowfall at 1920x1080",
        "",
        f"The 1080p street photo (8-bit, with its depth map) under {RATE_MM_H} mm/h of snow (liquid equivalent), the",
        "flake count set through `snow_near_m` (flakes in view go as its cube; two measurements and a cube root",
        "per row). Flakes: the frame's `stats['snow_flakes']` (generated in the voxels that can reach the view),",
        "streaks: those drawn. CPU 8-bit: `render_srgb8` (the fused photo path); CPU float and GPU: `render`.",
        f"Machine: {env['cpus']} CPU cores shared with other jobs, GPU {gpu_name}. Median wall time.",
        "",
        "| flakes (target) | snow_near_m | flakes | streaks | CPU 8-bit | CPU float | GPU float | CPU 8-bit vs fastest RandomSnow |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['target']:,} | {r['snow_near_m']:.2f} | {r['snow_flakes']:,} | {r['snow_streaks']:,} | {fmt(r['cpu_srgb8_s'])} | "
            f"{fmt(r['cpu_float_s'])} | {fmt(r['gpu_float_s'])} | {alb / r['cpu_srgb8_s']:.2f}x |"
        )
    lines += ["", "| peer, same image | time | images/s |", "|---|---|---|"]
    for p in peers:
        lines.append(f"| {p['impl']} | {p['s'] * 1e3:.1f} ms | {1 / p['s']:.1f} |")
    lines += [
        "",
        imgaug_note,
        "",
        "Koitabashi et al. report 150.5 / 50.6 / 27.0 fps at 1 000 / 5 000 / 10 000 flakes on a GeForce 6150 LE",
        "(their frame size is not given). Goals: at least albumentations' RandomSnow throughput (which draws no",
        "flakes) and 20x imgaug's Snowflakes (not measurable here, see above).",
    ]
    (RESULTS / "snow.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
