"""The GPU check (run by benches/device.sh): every effect rendered by the GPU backend beside
the CPU's, their 8-bit frames and layers compared (parity), then each row timed at 1080p on
both backends; writes gpu.md and gpu.json into --out.

Parity, per effect: the largest difference of the 8-bit sRGB frames in codes, the share of
pixel channels within 1 code, the SSIM (scikit-image) and the largest difference of each float
layer. An effect passes when 99.9 % of its channels lie within 1 code and its SSIM is at least
0.99; the script exits 1 when one fails, so it can gate. ``--small`` checks parity at 96 x 54
and times at 160 x 90 (a few seconds on lavapipe, inside ``make test``).

Timing: each row's median over ``--repeat`` frames after one untimed frame, the GPU's with its
upload and readback (what a user's ``render`` call costs), the CPU's on every core this machine
has (the far rain: SSIM alone, its GPU lookups being exact where the CPU's are interpolated). A
row the GPU backend refuses says so instead.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from timing import median_s

import skyfall
from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes


def _photo(width: int, height: int) -> PhotoScene:
    """The street at dusk rendered once on the CPU as a photo with its depth map."""
    clear = Renderer(width, height, backend="cpu").render(scenes.street(), Weather())
    return PhotoScene(io.to_srgb8(clear.rgb), clear.depth_m, camera=scenes.street().camera)


def effects(width: int, height: int) -> dict[str, tuple[Any, Weather, dict[str, Any]]]:
    """Each row: (scene, weather, render keywords)."""
    from skyfall.windshield import warm

    street = scenes.street()
    lamps = scenes.street(lamps=True, headlights=True)
    return {
        "rain + haze on a photo": (_photo(width, height), Weather(rain_rate_mm_h=25.0, visibility_m=2000.0), {}),
        "the street (ray cast, rain)": (street, Weather(rain_rate_mm_h=10.0), {}),
        "the street at dusk (lamps, glows)": (lamps, Weather(rain_rate_mm_h=10.0, sky_illuminance_lux=50.0), {}),
        "snow": (street, Weather(snow_rate_mm_h=3.0), {}),
        "clouds (broken)": (street, Weather(rain_rate_mm_h=1.0, clouds="broken"), {}),
        "windshield (rain preset)": (street, Weather(rain_rate_mm_h=10.0, windshield=warm("rain", 1.0)), {}),
        "far rain (rain_far_m = 2)": (street, Weather(rain_rate_mm_h=10.0, rain_near_m=5.0, rain_far_m=2.0), {}),
    }


def ssim8(a: np.ndarray, b: np.ndarray) -> float:
    from skimage.metrics import structural_similarity

    return float(structural_similarity(a, b, channel_axis=2))


def parity(width: int, height: int) -> list[dict[str, Any]]:
    rows = []
    cpu, gpu = Renderer(width, height, backend="cpu"), Renderer(width, height, backend="gpu")
    for name, (scene, weather, kw) in effects(width, height).items():
        row: dict[str, Any] = {"effect": name}
        c = cpu.render(scene, weather, seed=3, **kw)
        try:
            g = gpu.render(scene, weather, seed=3, **kw)
        except ValueError as exc:  # a refusal by name: the GPU backend has no pass for it
            row.update(status="refused", reason=str(exc).splitlines()[0])
            rows.append(row)
            continue
        c8, g8 = io.to_srgb8(c.rgb), io.to_srgb8(g.rgb)
        d = np.abs(c8.astype(int) - g8.astype(int))
        row["max_code_diff"] = int(d.max())
        row["within_1_code"] = float((d <= 1).mean())
        row["ssim"] = ssim8(c8, g8)
        row["layers_max_abs_diff"] = {k: float(np.nanmax(np.abs(np.where(np.isfinite(c.layers[k]), c.layers[k], 0) - np.where(np.isfinite(g.layers[k]), g.layers[k], 0)))) for k in c.layers if k in g.layers}
        # The far rain's GPU lookups are exact where the CPU interpolates them along 16-pixel
        # runs: a texel flips here and there, so its bar is the SSIM alone.
        close = row["within_1_code"] >= 0.999 or name.startswith("far rain")
        row["status"] = "pass" if close and row["ssim"] >= 0.99 else "FAIL"
        rows.append(row)
    return rows


def timing(width: int, height: int, repeat: int) -> list[dict[str, Any]]:
    rows = []
    cpu, gpu = Renderer(width, height, backend="cpu"), Renderer(width, height, backend="gpu")
    for name, (scene, weather, kw) in effects(width, height).items():
        row: dict[str, Any] = {"row": name, "frame": f"{width}x{height}"}
        row["cpu_s"] = median_s(lambda: cpu.render(scene, weather, seed=3, **kw), max(1, repeat // 2))
        try:
            row["gpu_s"] = median_s(lambda: gpu.render(scene, weather, seed=3, **kw), repeat)
            row["gpu_fps"] = 1.0 / row["gpu_s"]
            row["cpu_over_gpu"] = row["cpu_s"] / row["gpu_s"]
        except ValueError as exc:
            row["gpu_s"] = None
            row["gpu"] = "refused: " + str(exc).splitlines()[0]
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("benches/results"))
    ap.add_argument("--small", action="store_true", help="small frames: the lavapipe check inside make test")
    ap.add_argument("--repeat", type=int, default=None)
    args = ap.parse_args(argv)
    check = (96, 54) if args.small else (480, 270)
    timed = (160, 90) if args.small else (1920, 1080)
    repeat = args.repeat if args.repeat is not None else (2 if args.small else 10)
    t0 = time.perf_counter()
    probe = Renderer(16, 16, backend="gpu")
    adapter = probe.adapter_info or {}
    env = {
        "skyfall": skyfall.__version__,
        "skyfall_from": str(Path(skyfall.__file__).parent),
        "python": sys.version.split()[0],
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "adapter": adapter,
        "small": args.small,
    }
    par = parity(*check)
    times = timing(*timed, repeat)
    env["seconds"] = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "gpu.json").write_text(json.dumps({"env": env, "parity": par, "timing": times}, indent=2) + "\n")
    lines = [
        "# GPU check",
        "",
        f"Adapter: **{adapter.get('name', '?')}** ({adapter.get('device_type', '?')}, {adapter.get('backend', '?')}), driver {adapter.get('driver', '?') or '?'}; "
        f"skyfall {env['skyfall']} on Python {env['python']}, {env['cpus']} CPUs; {env['seconds']:.0f} s in all.",
        "",
        f"## Parity at {check[0]} x {check[1]} (GPU against CPU, 8-bit sRGB; pass: 99.9 % within 1 code and SSIM >= 0.99)",
        "",
        "| effect | status | max code diff | within 1 code | SSIM | largest layer difference |",
        "|---|---|---|---|---|---|",
    ]
    for r in par:
        if r["status"] == "refused":
            lines.append(f"| {r['effect']} | refused | — | — | — | {r['reason']} |")
            continue
        worst = max(r["layers_max_abs_diff"].items(), key=lambda kv: kv[1], default=("—", 0.0))
        lines.append(f"| {r['effect']} | {r['status']} | {r['max_code_diff']} | {100 * r['within_1_code']:.3f} % | {r['ssim']:.4f} | {worst[0]} {worst[1]:.2g} |")
    lines += ["", f"## Timing at {timed[0]} x {timed[1]} (median of {repeat} GPU frames, {max(1, repeat // 2)} CPU frames; GPU with upload and readback)", ""]
    lines += ["| row | CPU | GPU | GPU fps | CPU / GPU |", "|---|---|---|---|---|"]
    for r in times:
        if r["gpu_s"] is None:
            lines.append(f"| {r['row']} | {1e3 * r['cpu_s']:.1f} ms | {r['gpu']} | — | — |")
        else:
            lines.append(f"| {r['row']} | {1e3 * r['cpu_s']:.1f} ms | {1e3 * r['gpu_s']:.1f} ms | {r['gpu_fps']:.1f} | {r['cpu_over_gpu']:.2f}x |")
    (args.out / "gpu.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    failed = [r["effect"] for r in par if r["status"] == "FAIL"]
    if failed:
        print(f"parity failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
