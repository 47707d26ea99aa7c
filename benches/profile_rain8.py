"""Where a fused 8-bit frame's work goes (rain_rate 10 mm/h on the 1080p street photo, and its haze
alone): instructions per stage under callgrind at the AVX2 level and with the scalar twins, and
CPU time per stage under perf at the CPU's own level. Run by benches/bench_rain.py (its "What is
left" section); `python benches/profile_rain8.py` prints the numbers. Either tool missing: the
part is skipped and says so.

Callgrind counts instructions exactly whatever the machine's load (valgrind has no AVX-512, so
the dispatch picks AVX2 under it); a stage is the inclusive count of its functions, per frame the
difference between a run of three frames and a run of one, halved. perf samples the CPU time of
every thread at 1 kHz; a stage is the self time of the functions its pattern names.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

W, H = 1920, 1080
# stage -> functions (as callgrind_annotate prints them), counted inclusive
STAGES: dict[str, tuple[str, ...]] = {
    "shade: decode, haze, rain map, encode": ("skyfall_core::frame::srgb8::shade_row_at",),
    "transmittance (haze exponential, sky path)": (
        "skyfall_core::simd::transmittance_row_scalar",
        "skyfall_core::simd::avx2::transmittance_row",
        "skyfall_core::simd::avx512::transmittance_row",
    ),
    "raster: streaks into each tile's P, Q": ("skyfall_core::frame::srgb8::raster_tile",),
    "binning streaks by tile": ("skyfall_core::particles::binning::bin_by_tiles",),
    "drops: generation, light, projection, sort": ("skyfall_core::frame::passes::Particles::prepare",),
    "depth map check": ("skyfall_core::haze::check_depth",),
}
# stage -> regex over perf's "dso symbol", self time; the first that matches
TIME_STAGES: dict[str, str] = {
    "shade: decode, haze, rain map, encode": r"_core\S* .*shade_row",
    "transmittance (haze exponential, sky path)": r"_core\S* .*transmittance_row",
    "raster: streaks into each tile's P, Q": r"_core\S* .*(raster_tile|composite|walk)",
    "rest of the core (drops, binning, checks, threads)": r"^_core",
    "Python and numpy (the scene's airlight estimate, checks)": r"^(libpython|_multiarray|python|libc|ld-linux|libm)",
    "kernel (page faults, scheduling)": r"^\[kernel",
    "other": r".",
}


def worker(mode: str, frames: int, data: str) -> None:
    """Render ``frames`` fused frames of ``mode`` ("rain" or "haze") from the saved photo."""
    from skyfall import PhotoScene, Renderer, Weather, scenes

    with np.load(data) as d:  # an npz reads (and checksums) an array at each access: once
        photo8, depth = d["photo8"], d["depth"]
    cpu = Renderer(W, H, backend="cpu")
    cam = scenes.street().camera
    w = Weather(rain_rate_mm_h=10.0) if mode == "rain" else Weather(rain_rate_mm_h=10.0, rain_streaks=False)
    out = np.empty_like(photo8)
    for _ in range(frames):
        cpu.render_srgb8(PhotoScene(photo8, depth, camera=cam), w, out=out)


def _save_photo(tmp: Path) -> str:
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_rain import street_photo

    from skyfall import Renderer

    p = street_photo(Renderer(W, H, backend="cpu"))
    path = tmp / "photo.npz"
    np.savez(path, photo8=p.photo8, depth=p.depth)
    return str(path)


def _callgrind(mode: str, level: str, frames: int, data: str, tmp: Path) -> dict[str, float]:
    """Inclusive instructions per stage, and the process's total, of a run of ``frames``."""
    out = tmp / f"cg.{mode}.{level}.{frames}"
    env = dict(os.environ, RAYON_NUM_THREADS="1", SKYFALL_SIMD=level)
    subprocess.run(
        ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable, __file__, "--worker", mode, str(frames), data],
        env=env,
        check=True,
        capture_output=True,
    )
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)], check=True, capture_output=True, text=True).stdout
    counts: dict[str, float] = {}
    total = re.search(r"([\d,]+) \([^)]*\)\s+PROGRAM TOTALS", text)
    counts["whole process"] = float(total.group(1).replace(",", "")) if total else 0.0
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+) \([^)]*\)\s+\S*?:(.+?)(?: \[[^\]]*\])?$", line)
        if not m:
            continue
        name = m.group(2).strip()
        for stage, fns in STAGES.items():
            if name in fns:
                counts[stage] = counts.get(stage, 0.0) + float(m.group(1).replace(",", ""))
    return counts


def _perf_ms(mode: str, frames: int, data: str, tmp: Path) -> dict[str, float]:
    """CPU ms by stage (self time) of a whole run of ``frames``."""
    out = tmp / f"perf.{mode}.{frames}"
    subprocess.run(["perf", "record", "-F", "1000", "-o", str(out), sys.executable, __file__, "--worker", mode, str(frames), data], check=True, capture_output=True)
    report = subprocess.run(
        ["perf", "report", "-i", str(out), "--no-children", "--sort", "dso,symbol", "--stdio", "-n"], check=True, capture_output=True, text=True
    ).stdout
    ms: dict[str, float] = {stage: 0.0 for stage in TIME_STAGES}
    for line in report.splitlines():
        m = re.match(r"\s*[\d.]+%\s+(\d+)\s+(\S+)\s+\[[.k]\]\s+(.+?)\s*$", line)
        if not m:
            continue
        samples, key = int(m.group(1)), f"{m.group(2)} {m.group(3)}"
        stage = next(st for st, pattern in TIME_STAGES.items() if re.search(pattern, key))
        ms[stage] += samples  # 1 kHz: one sample is 1 ms of CPU
    return ms


def _perf(mode: str, frames: int, data: str, tmp: Path) -> dict[str, float]:
    """CPU ms per frame by stage: a run of ``frames`` + 20 less a run of 20 (start-up, imports),
    over ``frames``."""
    short, long = (_perf_ms(mode, n, data, tmp) for n in (20, frames + 20))
    return {k: (long[k] - short[k]) / frames for k in TIME_STAGES}


def profile(frames: int = 100) -> dict[str, object]:
    """The bench's profile: {"instructions": {"rain.avx2": {stage: per frame}, ...}, "time":
    {"rain": {stage: CPU ms per frame}, ...}, "frames": n}, or {"skipped": why}."""
    have_cg = shutil.which("valgrind") and shutil.which("callgrind_annotate")
    have_perf = shutil.which("perf")
    if not have_cg and not have_perf:
        return {"skipped": "neither valgrind nor perf is installed"}
    result: dict[str, object] = {"frames": frames}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        data = _save_photo(tmp)
        if have_cg:
            ins: dict[str, dict[str, float]] = {}
            for mode in ("rain", "haze"):
                for level in ("avx2", "scalar"):
                    one, three = (_callgrind(mode, level, n, data, tmp) for n in (1, 3))
                    per = {k: (three.get(k, 0.0) - one.get(k, 0.0)) / 2 for k in [*STAGES, "whole process"]}
                    per["rest"] = per["whole process"] - sum(per[k] for k in STAGES)
                    ins[f"{mode}.{level}"] = per
            result["instructions"] = ins
        if have_perf:
            try:
                result["time"] = {mode: _perf(mode, frames, data, tmp) for mode in ("rain", "haze")}
            except subprocess.CalledProcessError as exc:  # perf without permission to sample
                result["time_skipped"] = str(exc)
    return result


if __name__ == "__main__":
    if sys.argv[1:2] == ["--worker"]:
        worker(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        import json

        print(json.dumps(profile(), indent=2))
