"""Sweeps at the speed of a frame (issue 31, item 1): a frame whose weather changes the sky
(a new rain rate, visibility or sky type) against a frame of a weather seen before, on the
bundled street at 640x360 on the CPU, in one run. Every "new" call draws a value never drawn
before, so its ambient-light map is always made again: from the scene's horizon
(``_core.AmbientHorizon``, found at the first frame) as skyfall does now, and, for the
comparison, from scratch as it did before (the horizon switched off for that row). A new sky
brightness E needs no new map (the map is relative to E). Also: the first map of a scene with
and without its horizon, the horizon's size, the relit map against the direct one, and the
overcast maps' error against the sky tabulated along every azimuth; and the
street dataset (issue 31, item 5): items of ``skyfall dataset --scene street`` (a jittered camera,
a new rain rate and visibility per item) rendered in this process with the map's extent around
the camera widened to ``sky.CAMERA_BOUNDS_STEP_M`` and, as before, not widened, and the CLI's
items/s on 1 and 2 workers.

Writes benches/results/sweeps.md and .json. Run with ``make bench``.
"""

from __future__ import annotations

import itertools
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from timing import block_times_s

from skyfall import Renderer, Weather, _core, scenes, sky

RESULTS = Path(__file__).parent / "results"
W, H = 640, 360


def main() -> None:
    r = Renderer(W, H, backend="cpu")
    street = scenes.street()
    seen = Weather(rain_rate_mm_h=5.0)
    r.render(street, seen)  # the scene's horizon and the seen weather's map
    n = itertools.count(1)
    steps = itertools.count(1)  # 20 grid rates in turn, more than the 16 texture sets kept: each a miss
    sweeps = {
        "rain rate": lambda: Weather(rain_rate_mm_h=5.0 + 1e-3 * next(n)),
        "visibility": lambda: Weather(rain_rate_mm_h=5.0, visibility_m=2000.0 - 0.5 * next(n)),
        "sky type and sun": lambda: Weather(sky=12, sun_elevation_deg=20.0 + 1e-3 * next(n), sun_azimuth_deg=185.0, rain_rate_mm_h=5.0),
        "sky brightness E": lambda: Weather(rain_rate_mm_h=5.0, sky_illuminance_lux=10000.0 + next(n)),
        # The far layers' textures are drawn at grid rates (skyfall_core::rain::far, 8 per
        # decade): a new rate within a grid step reuses them, a rate on a new grid step (what
        # every new rate cost before) makes them.
        "rain rate, far layers": lambda: Weather(rain_rate_mm_h=5.0 + 1e-3 * next(n), rain_far_m=2.0),
        "rain rate, far layers, a new grid step each": lambda: Weather(rain_rate_mm_h=10 ** ((next(steps) % 20) / 8), rain_far_m=2.0),
    }
    original = sky._horizon

    def without_horizon(*args: object, **kwargs: object) -> None:
        return None

    rows = []
    seen_far = Weather(rain_rate_mm_h=5.0, rain_far_m=2.0)
    r.render(street, seen_far)
    # A sky with a sun is swept against a frame of the same sky seen before (its sun's direct
    # light and shadow rays cost the frame itself more than an overcast frame).
    seen_sun = Weather(sky=12, sun_elevation_deg=20.0, sun_azimuth_deg=185.0, rain_rate_mm_h=5.0)
    r.render(street, seen_sun)
    for name, make in sweeps.items():
        seen_w = seen_far if "far" in name else seen_sun if "sun" in name else seen
        fns = {
            "seen": lambda s=seen_w: r.render(street, s),  # type: ignore[misc]
            "new": lambda m=make: r.render(street, m()),  # type: ignore[misc]
        }
        times = block_times_s(fns, blocks=5, per_block=3)
        sky._horizon = without_horizon  # type: ignore[assignment]
        try:
            before = block_times_s({"new_direct": lambda m=make: r.render(street, m())}, blocks=5, per_block=3)  # type: ignore[misc]
        finally:
            sky._horizon = original  # type: ignore[assignment]
        med = {k: float(np.median(v)) for k, v in {**times, **before}.items()}
        rows.append({
            "sweep": name, "seen_ms": 1e3 * med["seen"], "new_ms": 1e3 * med["new"], "new_direct_ms": 1e3 * med["new_direct"],
            "new_over_seen": float(np.median([a / b for a, b in zip(times["new"], times["seen"])])),
            "direct_over_seen": med["new_direct"] / med["seen"],
        })
        print(rows[-1])
    # The first map of a scene: its horizon found and lit, against the direct build.
    lo, hi = sky.default_bounds(street, 1.0)
    boxes = sky._occluders(street)
    model = Weather(rain_rate_mm_h=5.0).sky_model()
    kw = dict(bounds_min_m=list(lo), bounds_max_m=list(hi), spacing_m=1.0, samples=sky.MAP_SAMPLES)
    sun_model = Weather(sky=12, sun_elevation_deg=20.0, sun_azimuth_deg=185.0, rain_rate_mm_h=5.0).sky_model()
    first: dict[str, list[float]] = {"direct": [], "horizon": [], "light": [], "light_again": [], "light_sun": []}
    for _ in range(3):
        t = time.perf_counter()
        direct = model.ambient_map(boxes, **kw)
        first["direct"].append(time.perf_counter() - t)
        t = time.perf_counter()
        horizon = _core.ambient_horizon(boxes, **kw)
        first["horizon"].append(time.perf_counter() - t)
        horizon_mb = horizon.nbytes / 1e6
        t = time.perf_counter()
        relit = model.light_map(horizon)  # the first overcast sky: each node's weights made
        first["light"].append(time.perf_counter() - t)
        t = time.perf_counter()
        Weather(rain_rate_mm_h=5.5).sky_model().light_map(horizon)
        first["light_again"].append(time.perf_counter() - t)
        t = time.perf_counter()
        sun_model.light_map(horizon)
        first["light_sun"].append(time.perf_counter() - t)
    same = bool(np.array_equal(direct.values, relit.values) and np.array_equal(direct.solid, relit.solid))
    # The overcast maps' reading at 24 elevations against the sky tabulated along every azimuth
    # at 512 (per_azimuth=True): the worst open node, relative to its brightest channel.
    errors = {}
    for label, w in {"clear": Weather(), "5 mm/h": Weather(rain_rate_mm_h=5.0), "0.1 mm/h, 20 km": Weather(rain_rate_mm_h=0.1, visibility_m=20000.0),
                     "5 mm/h, 300 m": Weather(rain_rate_mm_h=5.0, visibility_m=300.0)}.items():
        m = w.sky_model()
        a, b = m.light_map(horizon), m.ambient_map(boxes, **kw, per_azimuth=True)
        o = ~b.solid.astype(bool)
        x, y = a.values[o].astype(np.float64), b.values[o].astype(np.float64)
        errors[label] = float((np.abs(x - y).max(axis=1) / np.maximum(np.abs(y).max(axis=1), 1e-6)).max())
    data = dataset_rows()
    fm = {k: 1e3 * float(np.median(v)) for k, v in first.items()}
    summary = {"rows": rows, "first_map_ms": fm, "horizon_mb": horizon_mb, "horizon_with_weights_mb": horizon.nbytes / 1e6,
               "map_nodes": int(np.prod(direct.dims)), "relit_equals_direct": same, "overcast_error": errors, "dataset": data}
    lines = [
        "# Sweeps at the speed of a frame: the ambient map lit from the scene's horizon",
        "",
        f"{W}x{H}, CPU backend, the bundled street, {platform.processor() or platform.machine()}, {len(os.sched_getaffinity(0))} cores; "
        "medians of 5 alternating blocks of 3 frames (benches/sweeps.py). Each 'new' frame's weather was never drawn before, "
        "so its map is made again: from the scene's horizon, an overcast sky (rain rate, visibility) as a dot product of each "
        "node's weights with the sky's integrals at 24 elevations, a sky with a sun from the edges along every azimuth "
        "(kept as 16-bit codes since stop 52: the street's horizon 32 MB, was 75; worst 3.0e-5 of a point's light against "
        "exact edges, skyfall-core's sky::illuminance tests); "
        "'from scratch' is the same sweep with the horizon switched off (skyfall before stop 40). The seen weather is "
        "5 mm/h of rain under the overcast sky, for the sky with a sun the same sky (type 12, the sun 20 deg up) "
        "(before stop 45 the overcast frame, which lacks the sun's direct light and shadow rays: 2.86x there).",
        "",
        "| sweep | seen weather, ms | new weather, ms | new / seen | from scratch, ms | from scratch / seen |",
        "|---|---|---|---|---|---|",
        *(f"| {x['sweep']} | {x['seen_ms']:.0f} | {x['new_ms']:.0f} | {x['new_over_seen']:.2f} | {x['new_direct_ms']:.0f} | "
          f"{x['direct_over_seen']:.2f} |" for x in rows),
        "",
        f"The scene's first map ({summary['map_nodes']} nodes, {sky.MAP_SAMPLES} azimuths): built directly {fm['direct']:.0f} ms; "
        f"its horizon found {fm['horizon']:.0f} ms ({horizon_mb:.0f} MB); the first overcast sky lit from it {fm['light']:.0f} ms "
        f"(each node's weights made: the horizon then holds {summary['horizon_with_weights_mb']:.0f} MB), a later one "
        f"{fm['light_again']:.1f} ms, a sky with a sun {fm['light_sun']:.0f} ms. The relit map equals the directly built one bit "
        f"for bit: {same}.",
        "",
        "The overcast maps against the sky tabulated along every azimuth at 512 elevations, the worst open node relative to its "
        "brightest channel (tested below 1e-3 in tests/test_sky.py): "
        + ", ".join(f"{k} {v:.1e}" for k, v in errors.items()) + ".",
        "",
        "## The street dataset",
        "",
        f"Items {DATASET_ITEMS[0]}-{DATASET_ITEMS[1] - 1} of `skyfall dataset --scene street` at {W}x{H} (rain 1-50 mm/h, visibility "
        "300-3000 m, the camera jittered by +-0.5 m and +-5 deg), each item's weather frame and clean frame rendered in this "
        "process after the items before them (so the scene's maps and horizon are warm), the median per item:",
        "",
        "| map extent around the camera | ms per item | the same frame equal |",
        "|---|---|---|",
        f"| as before (each camera's own) | {data['unwidened_ms']:.0f} | |",
        f"| widened to {sky.CAMERA_BOUNDS_STEP_M:g} m steps | {data['widened_ms']:.0f} | {data['frames_equal']} |",
        "",
        f"The CLI, {DATASET_N} items from a cold start (worker processes importing skyfall, each worker's first maps and "
        "horizon included): " + ", ".join(f"{k} worker(s) {v:.2f} items/s" for k, v in data["cli_items_s"].items()) + ".",
        "",
    ]
    RESULTS.mkdir(exist_ok=True)
    # the windshield's section is benches/windshield_warmup.py's: kept as it stands
    old = (RESULTS / "sweeps.md").read_text() if (RESULTS / "sweeps.md").exists() else ""
    kept = old[old.index("## The windshield's warm-up") :] if "## The windshield's warm-up" in old else ""
    (RESULTS / "sweeps.md").write_text("\n".join(lines).rstrip("\n") + ("\n\n" + kept if kept else "\n"))
    (RESULTS / "sweeps.json").write_text(json.dumps(summary, indent=1))
    print("\n".join(lines))


DATASET_ITEMS = (4, 12)
DATASET_N = 48


def _unwidened_bounds(scene: object, spacing_m: float, around_m: object = None, radius_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``sky.default_bounds`` before the camera's cube was widened: the cube as it is."""
    boxes = sky._occluders(scene).astype(np.float64)
    c = np.asarray(around_m, dtype=np.float64).reshape(1, 3)
    pts = np.concatenate([boxes[:, 0:3], boxes[:, 3:6], c - radius_m, c + radius_m], axis=0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    lo[1] = max(lo[1], 0.0)
    hi[1] = max(hi[1], lo[1]) + spacing_m
    return lo, hi


def dataset_rows() -> dict[str, object]:
    from skyfall.dataset.item import _street_camera, _weather
    from skyfall.dataset.sample import DatasetConfig, sample_item

    cfg = DatasetConfig(out=tempfile.gettempdir(), scene="street", width=W, height=H, rain_rate_mm_h=(1.0, 50.0), visibility_m=(300.0, 3000.0))
    street = scenes.street()

    def per_item(bounds: object) -> tuple[float, list[np.ndarray]]:
        original = sky.default_bounds
        sky.default_bounds = bounds  # type: ignore[assignment]
        try:
            r = Renderer(W, H, backend="cpu")
            times, frames = [], []
            for i in range(DATASET_ITEMS[1]):
                p = sample_item(cfg, i)
                cam = _street_camera(street.camera, p)
                t = time.perf_counter()
                frames.append(r.render_srgb8(street, _weather(cfg, p), camera=cam, seed=p.render_seed))
                r.render_srgb8(street, Weather(), camera=cam)
                times.append(time.perf_counter() - t)
            return float(np.median(times[DATASET_ITEMS[0]:])), frames
        finally:
            sky.default_bounds = original  # type: ignore[assignment]

    before_s, before = per_item(_unwidened_bounds)
    after_s, after = per_item(sky.default_bounds)
    cli = {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as out:
            run = subprocess.run(
                [str(Path(sys.executable).with_name("skyfall")), "dataset", "--scene", "street", "--out", out, "--variants", str(DATASET_N), "--width", str(W),
                 "--height", str(H), "--rain-rate", "1:50", "--visibility-m", "300:3000", "--workers", str(workers), "--no-progress"],
                capture_output=True, text=True, check=True,
            )
            found = re.search(r"([0-9.]+) items/s", run.stdout + run.stderr)
            cli[workers] = float(found.group(1)) if found else float("nan")
    return {
        "unwidened_ms": 1e3 * before_s,
        "widened_ms": 1e3 * after_s,
        "frames_equal": all(np.array_equal(a, b) for a, b in zip(before, after)),
        "cli_items_s": cli,
    }


if __name__ == "__main__":
    main()
