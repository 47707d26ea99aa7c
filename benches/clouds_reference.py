"""The frames' cloud lighting against a Monte Carlo path tracer (every order of scattering).

A small generated cumulus seen from 1.2 km under the sun, 32 x 32 pixels over a black sky:
the renderer's sun light (the frame under the sun less the same frame without it: the sky's
share cancels, compositing is linear in the light) with the diffuse term (frames' default) and
without it (single scattering alone), against `skyfall.clouds.path_traced` (all orders, and
its first order alone). Two suns: front-lit (behind the camera) and side-lit.

Writes benches/results/clouds_reference.md and .json. Run with `make bench`.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from skyfall import Camera, Renderer, Weather, _core, clouds, scenes

RESULTS = Path(__file__).parent / "results"
SIZE = 32
PATHS = int(os.environ.get("SKYFALL_REF_PATHS", "96"))
LUMA = np.array([0.2126, 0.7152, 0.0722])
"""Rec. 709 luminance: the sun's light has the sun's colour, of luminance 1 (`sky.colours`)."""
SUNS = {"front-lit (sun behind the camera, 35 deg up)": (35.0, 160.0), "side-lit (sun to the east, 30 deg up)": (30.0, 90.0)}


def directions(cam: Camera) -> np.ndarray:
    """Unit view directions of the pixels, (N, 3)."""
    d = cam.ray_directions().reshape(-1, 3)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def sun_light(r: Renderer, scene: scenes.BoxScene, w: Weather, cloud: clouds.Cloud, diffuse: bool) -> np.ndarray:
    """The frame's light from the sun alone, relative units (H, W), its luminance: the frame
    under the sun less the frame without it (the sky behind, dimmed alike, and the sky's light
    cancel)."""
    out = []
    for weather in (w, Weather(sky=w.sky, sun_elevation_deg=w.sun_elevation_deg, sun_azimuth_deg=w.sun_azimuth_deg, sun_illuminance_lux=0.0)):
        req = r._request(scene, weather)
        req["clouds"] = clouds.frame_field(cloud, weather.sun_direction, diffuse=diffuse)
        rgb, _, _, _ = _core.render_frame(req)
        out.append(rgb.astype(np.float64) @ LUMA)
    return out[0] - out[1]


class Measured(NamedTuple):
    """One cloud under one sun: the frames' sun light with and without the diffuse term, the
    path tracer's (every order, first order, standard error), its seconds, and the pixels it
    lights (more than 5 % of its maximum). Flat arrays over the pixels."""

    with_diffuse: np.ndarray
    single: np.ndarray
    mc: np.ndarray
    mc_first: np.ndarray
    mc_err: np.ndarray
    mc_s: float
    mask: np.ndarray


def measured(r: Renderer, scene: scenes.BoxScene, w: Weather, cloud: clouds.Cloud, eye: np.ndarray, dirs: np.ndarray, paths: int) -> Measured:
    """The frames' and the path tracer's light of `cloud` under `w`'s sun (its seed 1)."""
    with_d = sun_light(r, scene, w, cloud, True).reshape(-1)
    single = sun_light(r, scene, w, cloud, False).reshape(-1)
    t0 = time.perf_counter()
    mc, mc1, err = clouds.path_traced(cloud, w.sun_direction, sun_relative=w.sun_relative, eye_m=eye, directions=dirs, paths=paths, max_orders=512, seed=1)
    return Measured(with_d, single, mc, mc1, err, time.perf_counter() - t0, mc > 0.05 * mc.max())


def main() -> None:
    cloud = clouds.particles("cumulus", n_particles=600, extent_m=300.0, altitude_m=1000.0, seed=4)
    centre = cloud.positions_m.mean(axis=0)
    eye = centre + np.array([0.0, 0.0, 1200.0])
    cam = Camera(eye, vertical_fov_deg=18.0, width=SIZE, height=SIZE)
    sky_only = scenes.boxes([], ground=False, camera=cam)
    r = Renderer(SIZE, SIZE, backend="cpu")
    dirs = directions(cam.with_resolution(SIZE, SIZE))
    rows = []
    for name, (el, az) in SUNS.items():
        w = Weather(sky=12, sun_elevation_deg=el, sun_azimuth_deg=az)
        with_d, single_r, mc, mc1, err, mc_s, mask = measured(r, sky_only, w, cloud, eye, dirs, PATHS)

        def stats(a: np.ndarray, ref: np.ndarray) -> dict[str, float]:
            rel = a[mask] / ref[mask] - 1.0
            return {"median_abs": float(np.median(np.abs(rel))), "bias": float(np.median(rel)), "flux_ratio": float(a[mask].sum() / ref[mask].sum())}

        row = {
            "sun": name,
            "pixels": int(mask.sum()),
            "mc_paths": PATHS,
            "mc_s": mc_s,
            "mc_rel_std_err": float(np.median(err[mask] / mc[mask])),
            "multiple_share": float(1.0 - mc1[mask].sum() / mc[mask].sum()),
            "with_diffuse_vs_mc": stats(with_d, mc),
            "single_vs_mc": stats(single_r, mc),
            "single_vs_mc_single": stats(single_r, mc1),
        }
        rows.append(row)
        print(json.dumps(row), flush=True)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "clouds_reference.json").write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "rows": rows}, indent=2))
    lines = [
        "# The frames' cloud lighting against a Monte Carlo reference",
        "",
        f"{time.strftime('%Y-%m-%d')}. `clouds.particles('cumulus', n_particles=600, extent_m=300, seed=4)` seen from",
        f"1.2 km at its mid height, {SIZE} x {SIZE} px over the open sky, the sun's light alone (the frame under the",
        "sun less the same frame without it). Reference: `clouds.path_traced`, every order of scattering",
        f"({PATHS} paths per pixel, up to 512 vertices), and its first order alone. Statistics over the",
        "pixels where the reference exceeds 5 % of its maximum: median |ratio - 1|, median ratio - 1",
        "(bias), and the ratio of the summed light (flux).",
        "",
        "| sun | pixels | multiple scattering's share (MC) | MC std. err. | frames (with the diffuse term) vs MC: median error / bias / flux | single scattering alone vs MC | frames' single vs MC single |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        f = lambda s: f"{s['median_abs']:.0%} / {s['bias']:+.0%} / {s['flux_ratio']:.2f}"  # noqa: E731
        lines.append(
            f"| {row['sun']} | {row['pixels']} | {row['multiple_share']:.0%} | {row['mc_rel_std_err']:.1%} | "
            f"{f(row['with_diffuse_vs_mc'])} | {f(row['single_vs_mc'])} | {f(row['single_vs_mc_single'])} |"
        )
    (RESULTS / "clouds_reference.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
