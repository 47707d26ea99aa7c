"""Clouds in the sky's light: what the clouds' dome costs and how fine it must be.

A box scene's ambient-light map integrates the sky with its clouds in it (``_core.CloudDome``:
the clouds drawn by the frames' cloud pass on the upward faces of a cube around the scene). In
one run:

1. The dome at 16, 32 (the default), 64 and 128 px a face for the ``broken`` and
   ``stratocumulus`` presets under the demo's sun: its build time, and the open ground's light on
   the map's five normals against the 128 px dome's (the map integrates the dome, so coarse faces
   should do).
2. Frames of the street at 640 x 360 on the CPU under the ``broken`` preset: a frame whose
   weather was seen before (its map cached), the first frame of a new cloud field, and the frames
   of a sequence whose clouds drift in the wind (a new field each frame; the sky light's clouds
   move in 25 m steps), each with the clouds in
   the sky's light and with the clear sky's map instead (what frames drew before the clouds
   reached the map), timed in alternating blocks.

Writes benches/results/cloud_sky_light.md and .json. Run with `make bench`.
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import skyfall
from skyfall import Renderer, Weather, _core, clouds, scenes, sky
from skyfall._demo import STREET_CLOUDS

RESULTS = Path(__file__).parent / "results"
FACES = (16, 32, 64, 128)
PRESETS = ("broken", "stratocumulus")
W, H = 640, 360


def dome_rows() -> list[dict[str, object]]:
    rows = []
    for name in PRESETS:
        w = Weather(sky=12, sun_elevation_deg=50.0, sun_azimuth_deg=185.0, clouds=name, visibility_m=20_000.0)
        field = clouds.frame_field(w.clouds, w.sun_direction)
        model = w.sky_model()
        none = np.zeros((0, 9), np.float32)
        light = {}
        for px in FACES:
            times = []
            for _ in range(3):
                t0 = time.perf_counter()
                dome = _core.CloudDome(field, model, (0.0, 0.0, 0.0), w.sun_relative, px)
                times.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            m = model.ambient_map(none, bounds_min_m=[0, 0, 0], bounds_max_m=[0, 0, 0], spacing_m=1.0, samples=sky.MAP_SAMPLES, dome=dome)
            table_s = time.perf_counter() - t0
            light[px] = m.values.reshape(-1)
            rows.append({"preset": name, "face_px": px, "dome_s": statistics.median(times), "table_s": table_s, "light": light[px].tolist()})
        clear = model.ambient_map(none, bounds_min_m=[0, 0, 0], bounds_max_m=[0, 0, 0], spacing_m=1.0, samples=sky.MAP_SAMPLES)
        for row in rows[-len(FACES) :]:
            row["max_rel_vs_128"] = float(np.max(np.abs(np.asarray(row["light"]) / light[128] - 1)))
            row["clear"] = clear.values.reshape(-1).tolist()
    return rows


def _clear_sky_light() -> object:
    """sky.cached_core_map with the clouds left out of the sky's light (the clear sky's map)."""
    own = sky.cached_core_map

    def clear(*args: object, **kwargs: object) -> object:
        return own(*args[:7], **kwargs)  # type: ignore[arg-type]

    return clear


def frame_rows() -> dict[str, dict[str, list[float]]]:
    scene = scenes.street()
    cam = STREET_CLOUDS.camera()
    r = Renderer(W, H, backend="cpu")
    own, clear = sky.cached_core_map, _clear_sky_light()
    modes = {"clouds in the sky light": own, "clear sky's map": clear}
    out: dict[str, dict[str, list[float]]] = {m: {"seen": [], "first": [], "drifting": []} for m in modes}
    sunny = {"sky": 12, "sun_elevation_deg": 50.0, "sun_azimuth_deg": 185.0, "visibility_m": 20_000.0}
    for block in range(4):
        for mode, fn in modes.items():
            sky.cached_core_map = fn  # type: ignore[assignment]
            try:
                # A new cloud field each block (a new seed), so its first frame builds anew.
                cloud = clouds.particles("broken", n_particles=36_000, seed=100 + 2 * block + (mode == "clear sky's map"))
                w = Weather(**sunny, clouds=cloud)  # type: ignore[arg-type]
                t0 = time.perf_counter()
                r.render(scene, w, camera=cam)
                out[mode]["first"].append(time.perf_counter() - t0)
                times = []
                for _ in range(3):
                    t0 = time.perf_counter()
                    r.render(scene, w, camera=cam)
                    times.append(time.perf_counter() - t0)
                out[mode]["seen"].append(statistics.median(times))
                windy = Weather(**sunny, clouds=cloud, wind_m_s=(10.0, 0.0, 0.0))  # type: ignore[arg-type]
                times = []
                for k in range(1, 5):
                    t0 = time.perf_counter()
                    r.render(scene, windy, camera=cam, time_s=(block * 10 + k) / 30.0)
                    times.append(time.perf_counter() - t0)
                out[mode]["drifting"].append(statistics.median(times))
            finally:
                sky.cached_core_map = own  # type: ignore[assignment]
    return out


def main() -> None:
    load_before = os.getloadavg()[0]
    domes = dome_rows()
    frames = frame_rows()
    env = {"cpus": os.cpu_count(), "machine": platform.machine(), "date": time.strftime("%Y-%m-%d"), "load_average": [load_before, os.getloadavg()[0]]}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "cloud_sky_light.json").write_text(json.dumps({"env": env, "domes": domes, "frames": frames, "skyfall": skyfall.__version__}, indent=2))
    lines = [
        "# Clouds in the sky's light (the ambient-light map's dome)",
        "",
        f"{env['date']}, {env['cpus']} CPUs ({env['machine']}); 1-minute load average {load_before:.1f} before, "
        f"{os.getloadavg()[0]:.1f} after (other work shares the cores: times are upper bounds).",
        "",
        "## The dome's faces",
        "",
        "The presets under the demo's sun (type 12, 50 deg up, azimuth 185 deg), seen from the origin. Light: the",
        "open ground's map on its five normals (up, +X, -X, +Z, -Z; relative to the clear sky's E), built from",
        f"the dome with {sky.MAP_SAMPLES} azimuths. Dome: median of 3 builds; table: the clouded sky's tables and the",
        "map, once.",
        "",
        "| preset | face px | dome | table + map | light (up, +X, -X, +Z, -Z) | clear sky's | max |rel| vs 128 px |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in domes:
        light = ", ".join(f"{v:.4f}" for v in row["light"])  # type: ignore[union-attr]
        clear = ", ".join(f"{v:.3f}" for v in row["clear"])  # type: ignore[union-attr]
        lines.append(
            f"| {row['preset']} | {row['face_px']} | {row['dome_s'] * 1e3:.0f} ms | {row['table_s'] * 1e3:.0f} ms | {light} | {clear} | "  # type: ignore[operator]
            f"{row['max_rel_vs_128']:.4f} |"
        )
    lines += [
        "",
        "## Frames",
        "",
        f"The demo's street and camera at {W} x {H}, CPU, under a `broken` field of 36,000 particles (a new seed",
        "per block and mode, so each block's first frame builds the field's volumes, its dome and its map).",
        "'Seen': the median of 3 frames of that weather again (everything cached). 'Drifting': the median of",
        "4 frames of a sequence in a 10 m/s wind (a new field and its volumes each frame; the sky light's dome and map once per 25 m step of drift, `clouds.SKY_DRIFT_STEP_M`, none within these frames). 'Clear sky's",
        "map': the same frames with the clouds left out of the map (`sky.cached_core_map` without them: what",
        "frames drew before). Four blocks, the modes in turn; each cell lists the blocks' times.",
        "",
        "| frames | clouds in the sky light | clear sky's map | ratio of medians |",
        "|---|---|---|---|",
    ]
    a, b = frames["clouds in the sky light"], frames["clear sky's map"]
    for k in ("seen", "first", "drifting"):
        fa, fb = statistics.median(a[k]), statistics.median(b[k])
        lines.append(f"| {k} | {', '.join(f'{v * 1e3:.0f}' for v in a[k])} ms | {', '.join(f'{v * 1e3:.0f}' for v in b[k])} ms | {fa / fb:.2f} |")
    (RESULTS / "cloud_sky_light.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
