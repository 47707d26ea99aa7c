"""Datasets at 1080p: items/s of rain + haze items on 1 and 2 workers, with the per-item cost
split (read, render, encode, write), locally and through a Dask LocalCluster, each worker's peak memory, and the PNG level's cost.

Inputs: 4 photos at 1920x1080 (scikit-image's photos tiled) with depth maps of the street as
.npy; items: 1-50 mm/h rain, 300-3000 m visibility, 1/250-1/30 s, rain_alpha ground truth
(the fused 8-bit path), PNG level 1. Writes benches/results/dataset.md and dataset.json.
Run with `.venv/bin/python benches/bench_dataset.py` (about a minute on 2 cores).
"""

from __future__ import annotations

import json
import os
import platform
import resource
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from skyfall import Renderer, dataset, io, scenes
from skyfall.dataset.io import PNG_FILTER_SUB

RESULTS = Path(__file__).parent / "results"
W, H = 1920, 1080
PHOTOS = 4
VARIANTS = 4  # 16 items per configuration


def make_inputs(root: Path) -> tuple[Path, Path]:
    """Photos with a real photo's texture (scikit-image's, tiled to 1920x1080: a flat render
    compresses far better than a photo and would flatter the PNG cost), each with the depth map of
    a clear 1080p street frame."""
    from skimage import data

    img, dep = root / "img", root / "depth"
    img.mkdir()
    dep.mkdir()
    r = Renderer(W, H, backend="cpu")
    sources = [data.coffee(), data.chelsea(), data.astronaut(), data.rocket()]
    for k in range(PHOTOS):
        src = sources[k % len(sources)]
        tiled = np.tile(src, (H // src.shape[0] + 1, W // src.shape[1] + 1, 1))[:H, :W]
        io.write_image(img / f"photo_{k}.png", np.ascontiguousarray(tiled))
        np.save(dep / f"photo_{k}.npy", r.render(scenes.street(seed=k)).depth_m)
    return img, dep


def run_dask(img: Path, dep: Path, out: Path) -> dict[str, object]:
    """Two single-threaded Dask workers of a LocalCluster on loopback."""
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}) as cluster, Client(cluster) as client:
        client.run(lambda: None)  # the workers are up before the clock starts

        def worker_cpu() -> float:
            times = client.run(lambda: sum(resource.getrusage(resource.RUSAGE_SELF)[:2]))
            return float(sum(times.values()))

        row = run(img, dep, out, 2, 1, worker_cpu=worker_cpu, scheduler=client)
    row["via"] = "Dask LocalCluster"
    return row


def cpu_s() -> float:
    """CPU time of this process and of its children that have ended (a run's worker processes
    are joined when it returns), s."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def one_at_a_time(img: Path, dep: Path, out: Path) -> dict[str, object]:
    """The items in this process without the pipeline: each rendered, then written
    (``render_item`` in a loop: what ``generate`` did before), the same run's baseline."""
    from skyfall.dataset.item import Worker, render_item

    shutil.rmtree(out, ignore_errors=True)
    config = dataset.DatasetConfig(out=out, input=img, depth=dep, variants=VARIANTS, seed=1, rain_rate_mm_h="1:50", visibility_m="300:3000")
    (out / "items").mkdir(parents=True)
    worker = Worker(config)
    c0, t0 = cpu_s(), time.perf_counter()
    cost = {k: 0.0 for k in ("read", "render", "encode", "write")}
    done: list[float] = []
    for src in dataset.sources(config):
        assert render_item(worker, src, cost)["status"] == "ok"
        done.append(time.perf_counter())
    wall = time.perf_counter() - t0
    n = len(done)
    return {
        "via": "local, one item at a time",
        "workers": 1,
        "threads_per_worker": os.cpu_count(),
        "items": n,
        "seconds": wall,
        "items_per_s": n / wall,
        "steady_items_per_s": (n - 1) / (done[-1] - done[0]),
        **{f"{k}_ms": 1e3 * v / n for k, v in cost.items()},
        "bytes_per_item": sum(p.stat().st_size for p in (out / "items").iterdir()) / n,
        "busy": (cpu_s() - c0) / (wall * (os.cpu_count() or 1)),
    }


def run(img: Path, dep: Path, out: Path, workers: int, threads: int | None, worker_cpu: Any = None, **extra: object) -> dict[str, object]:
    shutil.rmtree(out, ignore_errors=True)
    c0 = cpu_s() + (worker_cpu() if worker_cpu else 0.0)
    s = dataset.generate(
        out=out, input=img, depth=dep, variants=VARIANTS, seed=1, rain_rate_mm_h="1:50", visibility_m="300:3000",
        workers=workers, threads_per_worker=threads, progress=False, **extra,
    )
    used = cpu_s() + (worker_cpu() if worker_cpu else 0.0) - c0
    assert s.errors == 0, s.error_messages
    n = max(s.generated, 1)
    return {
        "busy": used / (s.seconds * (os.cpu_count() or 1)),
        "workers": workers,
        "threads_per_worker": threads if threads is not None else os.cpu_count(),
        "items": s.generated,
        "seconds": s.seconds,
        "items_per_s": s.items_per_s,
        "steady_items_per_s": s.steady_items_per_s,
        **{f"{k}_ms": 1e3 * v / n for k, v in s.cost_s.items()},
        "bytes_per_item": sum(p.stat().st_size for p in (out / "items").iterdir()) / n,
    }


def png_levels(img: Path, root: Path) -> list[dict[str, float]]:
    image = io.read_image(next(img.iterdir()))
    codes = io.to_srgb8(image)
    rows = []
    for filt in ("adaptive", "sub"):
        for level in (0, 1, 6, 9):
            meta: dict[str, int] = {"png:compressionLevel": level}
            if filt == "sub":
                meta["png:filter"] = PNG_FILTER_SUB
            times = []
            for _ in range(3):
                p = root / f"level{level}.png"
                t0 = time.perf_counter()
                io.write_image(p, codes, metadata=meta)
                times.append(time.perf_counter() - t0)
            rows.append({"filter": filt, "level": level, "ms": 1e3 * min(times), "mb": p.stat().st_size / 1e6})
    return rows


ROUNDS = 3  # every configuration once per round, interleaved: a busy spell weighs on all alike
CONFIGS = (
    ("s", 1, None, {"sequential": True}),  # in this process, one item at a time (no pipeline)
    ("a", 1, None, {}),  # in this process, the renderer on every core
    ("b", 1, 1, {}),  # one single-threaded worker
    ("c", 2, 1, {}),  # two single-threaded workers
    ("d", 2, None, {}),  # two workers sharing the cores
    ("e", 2, None, {"layers": ("rain_alpha", "rain_depth_m", "transmittance")}),  # the float path
    ("f", 2, 1, {"dask": True}),  # two single-threaded Dask workers
)


def main() -> None:
    load_before = os.getloadavg()[0]
    root = Path(tempfile.mkdtemp(prefix="bench_dataset_"))
    try:
        img, dep = make_inputs(root)
        runs: dict[str, list[dict[str, object]]] = {c[0]: [] for c in CONFIGS}
        for _ in range(ROUNDS):
            for key, workers, threads, extra in CONFIGS:
                if extra.get("dask"):
                    runs[key].append(run_dask(img, dep, root / key))
                elif extra.get("sequential"):
                    runs[key].append(one_at_a_time(img, dep, root / key))
                else:
                    runs[key].append(run(img, dep, root / key, workers, threads, **extra))  # type: ignore[arg-type]
        same = all(
            (root / "b" / "items" / p.name).read_bytes() == p.read_bytes()
            for run_dir in ("s", "a", "c", "d", "f")
            for p in (root / run_dir / "items").iterdir()
        )
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        levels = png_levels(img, root)
    finally:
        shutil.rmtree(root, ignore_errors=True)

    def rate(key: str, k: int) -> float:
        return float(runs[key][k]["steady_items_per_s"])  # type: ignore[arg-type]

    rows = []
    for key, *_ in CONFIGS:
        by_rate = sorted(runs[key], key=lambda r: float(r["steady_items_per_s"]))  # type: ignore[arg-type]
        median = dict(by_rate[len(by_rate) // 2])
        median["range"] = (float(by_rate[0]["steady_items_per_s"]), float(by_rate[-1]["steady_items_per_s"]))  # type: ignore[arg-type]
        rows.append(median)
    speedups = [rate("c", k) / rate("b", k) for k in range(ROUNDS)]
    overheads = [rate("c", k) / rate("f", k) - 1.0 for k in range(ROUNDS)]
    pipeline = [rate("a", k) / rate("s", k) for k in range(ROUNDS)]
    speedup = sorted(speedups)[ROUNDS // 2]
    dask_overhead = sorted(overheads)[ROUNDS // 2]
    RESULTS.mkdir(exist_ok=True)
    meta = {
        "machine": platform.platform(),
        "cpus": os.cpu_count(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
    }
    (RESULTS / "dataset.json").write_text(json.dumps({"meta": meta, "rows": rows, "runs": runs, "speedups": speedups, "dask_overheads": overheads, "png_levels": levels, "pipeline_gains": pipeline, "peak_worker_mb": peak_mb, "bytes_identical_1_vs_2_workers": same}, indent=1) + "\n")
    lines = [
        "# Datasets at 1080p",
        "",
        f"{meta['date']}, {meta['machine']}, {meta['cpus']} CPUs shared with other builds (1-minute load average {load_before:.1f}",
        f"before the run, {meta['load_after']:.1f} after: the figures move from minute to minute, and two workers only scale on idle cores).",
        f"{PHOTOS} photos 1920x1080 (scikit-image's coffee, chelsea, astronaut, rocket tiled) with the street's depth as .npy,",
        f"{VARIANTS} variants each: rain 1-50 mm/h, visibility 300-3000 m,",
        "exposure 1/250-1/30 s, PNG level 1 with the SUB filter; rain_alpha as .npy (the fused 8-bit path) unless said. Costs are per item,",
        "summed over the workers (so with 2 workers they add up to about twice the wall time per item).",
        "",
        f"Each configuration ran {ROUNDS} times, interleaved. items/s: the median run's steady rate, from its first item's completion",
        "to its last (the range over the runs in brackets), and with the workers' start (spawned processes importing numpy and",
        "skyfall, about a second each; the Dask cluster's start is not timed). The costs are the median run's.",
        "",
        "| via | workers | threads each | layers | items/s | with start | cores busy | read ms | render ms | encode ms | write ms | MB per item |",
        "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for (key, *_), r in zip(CONFIGS, rows):
        layers = "all three (float path)" if key == "e" else "rain_alpha"
        lines.append(
            f"| {r.get('via', 'local')} | {r['workers']} | {r['threads_per_worker']} | {layers} | {r['steady_items_per_s']:.2f} ({r['range'][0]:.2f}-{r['range'][1]:.2f}) | {r['items_per_s']:.2f} | {100 * float(r['busy']):.0f} % | {r['read_ms']:.0f} | {r['render_ms']:.0f} | "  # type: ignore[arg-type]
            f"{r['encode_ms']:.0f} | {r['write_ms']:.0f} | {float(r['bytes_per_item']) / 1e6:.1f} |"  # type: ignore[arg-type]
        )
    lines += [
        "",
        f"The pipeline (an item encoded and written while the next renders) against one item at a time, in this process",
        f"(steady rates): {sorted(pipeline)[ROUNDS // 2]:.2f}x, median of the rounds' ({', '.join(f'{x:.2f}' for x in pipeline)}).",
        "cores busy: CPU time of the run's processes (this one, its workers) over wall time x cores, start included.",
        f"Two single-threaded workers against one (steady rates): {speedup:.2f}x, median of the rounds' ratios ({', '.join(f'{x:.2f}' for x in speedups)}; goal 1.8x).",
        f"Dask's two single-threaded workers against the local two (steady rates): {100 * dask_overhead:+.0f} % wall time per item, median of",
        f"the rounds' ({', '.join(f'{100 * x:+.0f}' for x in overheads)} %; goal <= 10 %; the cluster's start is not timed).",
        f"Files of 1 worker, 2 workers and Dask byte-identical: {same}.",
        f"Peak resident memory of a worker process: {peak_mb:.0f} MB.",
        "",
        "read: the photo, its depth map, the scene and its airlight estimate; render: the weather frame; encode: sRGB",
        "encoding and OpenImageIO's PNG writes (zlib) of the weather and clean images (a photo's clean PNG is encoded once",
        "per worker and its bytes copied for its other variants); write: the layers' .npy, the",
        "checksums, the renames and the manifest row.",
        "",
        "One 1080p photo written as PNG through OpenImageIO at each zlib level (`png:compressionLevel`), with libpng's",
        "default adaptive filters and with the SUB filter the dataset uses (`png:filter` 16), best of 3:",
        "",
        "| filter | level | ms | MB |",
        "|---|---:|---:|---:|",
        *(f"| {r['filter']} | {r['level']} | {r['ms']:.0f} | {r['mb']:.2f} |" for r in levels),
        "",
    ]
    (RESULTS / "dataset.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
