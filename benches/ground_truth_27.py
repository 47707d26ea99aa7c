"""Issue 27's ground truth: each measured against a reference computed here from the literature
(numpy/scipy), never from the renderer's own numbers.

    python benches/ground_truth_27.py --json out.json      # measure this build
    python benches/ground_truth_27.py --md before.json after.json   # the table

1. rain_alpha over 1 - exp(-beta L) by column bands and top/bottom rows (drops, 640 x 360,
   25 mm/h, rain_near_m = 10 m, 60 deg vertical field of view, photo at infinity), beta the
   Marshall-Palmer integral of pi D^2 / 4 over the drawn bins.
2. billboards over drops by thirds of the frame, top to bottom (the defaults, 8 seeds).
3. -ln T / L of rays shorter than snow_near_m (10 mm/h of snow) and rain_near_m (25 mm/h),
   against the undrawn share of sigma.
5. the windshield's arrival over the whole Marshall-Palmer integral.
6. the far level of detail's mean rain_alpha over the per-drop reference (640 x 360).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
from scipy import integrate

from skyfall import Camera, PhotoScene, Renderer, Weather
from skyfall import physics

W, H = 640, 360
MP_N0 = 8000.0  # per m^3 per mm
RHO_W = 998.2  # water at 20 degC, kg/m^3 (the windshield's)


def mp_slope(rate: float) -> float:
    return 4.1 * rate**-0.21


def bins(diameters: tuple[float, ...]) -> list[tuple[float, float]]:
    d = np.asarray(diameters)
    mids = 0.5 * (d[1:] + d[:-1])
    lo = np.concatenate([[d[0] - (mids[0] - d[0])], mids])
    hi = np.concatenate([mids, [d[-1] + (d[-1] - mids[-1])]])
    return list(zip(np.maximum(lo, 0.0), hi, strict=True))


def beta_drawn(rate: float, diameters: tuple[float, ...]) -> float:
    lam = mp_slope(rate)
    f = lambda d: MP_N0 * math.exp(-lam * d) * math.pi * d * d / 4.0 * 1e-6  # noqa: E731
    return sum(integrate.quad(f, lo, hi)[0] for lo, hi in bins(diameters))


def photo(cam: Camera, depth: float = np.inf) -> PhotoScene:
    img = np.full((H, W, 3), 0.1, np.float32)
    return PhotoScene(img, np.full((H, W), depth, np.float32), camera=cam, encoding="linear", airlight="sky")


def item1(r: Renderer) -> dict[str, float]:
    w = Weather(rain_rate_mm_h=25.0, rain_near_m=10.0, rain_method="drops")
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    scene = photo(cam)
    a = np.mean([r.render(scene, w, seed=s).layers["rain_alpha"] for s in range(4)], axis=0)
    # The ray's length in the region: the sphere's radius less the near clip (0.05 m along z;
    # the rays have camera z = -1).
    length = 10.0 - 0.05 * np.linalg.norm(cam.with_resolution(W, H).ray_directions(), axis=-1)
    want = 1.0 - np.exp(-beta_drawn(25.0, w.rain_diameters_mm) * length)
    ratio = a / want
    out = {"mean": float(a.mean() / want.mean())}
    for name, x in [("centre", 0.5), ("35% of width", 0.85), ("edge", 0.97)]:
        c = int(x * W)
        out[f"column {name}"] = float(a[:, c - 8 : c + 8].mean() / want[:, c - 8 : c + 8].mean())
    out["top 45 rows"] = float(a[:45].mean() / want[:45].mean())
    out["bottom 45 rows"] = float(a[-45:].mean() / want[-45:].mean())
    out["worst band of 8x8"] = float(
        np.max(np.abs(ratio.reshape(8, H // 8, 8, W // 8).mean(axis=(1, 3)) - 1.0))
    )
    return out


def item2(r: Renderer) -> dict[str, float]:
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    scene = photo(cam)
    got = {}
    for method in ("billboards", "drops"):
        w = Weather(rain_rate_mm_h=25.0, rain_method=method)
        got[method] = np.mean([r.render(scene, w, seed=s).layers["rain_alpha"] for s in range(8)], axis=0)
    b, d = got["billboards"], got["drops"]
    out = {"mean": float(b.mean() / d.mean())}
    for k, name in enumerate(("top third", "middle third", "bottom third")):
        rows = slice(k * H // 3, (k + 1) * H // 3)
        out[name] = float(b[rows].mean() / d[rows].mean())
    out["top 45 rows"] = float(b[:45].mean() / d[:45].mean())
    out["bottom 45 rows"] = float(b[-45:].mean() / d[-45:].mean())
    return out


def snow_sigma(rate: float, s_min_mm: float | None) -> float:
    """Gunn & Marshall's slope, Locatelli & Hobbs' mass and speed, Mitchell's area; N0 from the
    flux; truncated at S = 10 mm. sigma = int N 2 A dD, over melted D below s_min's (None: all)."""
    lam = 2.55 * rate**-0.48
    size = lambda d: (math.pi / 6 * d**3 / 0.073) ** (1 / 1.4)  # noqa: E731
    melted = lambda s: (0.073 * s**1.4 * 6 / math.pi) ** (1 / 3)  # noqa: E731
    dmax = melted(10.0)
    flux = integrate.quad(lambda d: math.exp(-lam * d) * math.pi / 6 * d**3 * 0.8 * size(d) ** 0.16, 0, dmax)[0]
    n0 = rate * 1e6 / 3600.0 / flux
    hi = dmax if s_min_mm is None else melted(s_min_mm)
    return integrate.quad(lambda d: n0 * math.exp(-lam * d) * 2 * 0.3012 * size(d) ** 1.88, 0, hi, limit=200)[0] * 1e-6


def item3(r: Renderer) -> dict[str, float]:
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    out = {}
    # Snow: rays 4 m deep (shorter than snow_near_m = 8 m).
    w = Weather(snow_rate_mm_h=10.0, snow_near_m=8.0)
    f = r.render(photo(cam, 4.0), w, seed=0)
    dist = 4.0 * np.linalg.norm(cam.with_resolution(W, H).ray_directions(), axis=-1)
    got = float(np.mean(-np.log(f.layers["transmittance"]) / dist))
    out["snow: -ln T / L, 1/m"] = got
    out["snow: sigma_snow, 1/m"] = snow_sigma(10.0, None)
    out["snow: undrawn share of sigma (S < 1 mm), 1/m"] = snow_sigma(10.0, 1.0)
    # Rain: rays 3 m deep (rain_near_m = 5 m), 25 mm/h.
    w = Weather(rain_rate_mm_h=25.0)
    f = r.render(photo(cam, 3.0), w, seed=0)
    dist = 3.0 * np.linalg.norm(cam.with_resolution(W, H).ray_directions(), axis=-1)
    got = float(np.mean(-np.log(f.layers["transmittance"]) / dist))
    lam = mp_slope(25.0)
    total = integrate.quad(lambda d: MP_N0 * math.exp(-lam * d) * 2 * math.pi * d * d / 4 * 1e-6, 0, np.inf)[0]
    out["rain: -ln T / L, 1/m"] = got
    out["rain: sigma_rain, 1/m"] = total
    out["rain: undrawn share of sigma, 1/m"] = total - 2 * beta_drawn(25.0, w.rain_diameters_mm)
    return out


def item5() -> dict[str, float]:
    from skyfall.windshield import Windshield

    out = {}
    for rate, speed, tilt in [(2.0, 10.0, 30.0), (10.0, 0.0, 30.0), (50.0, 25.0, 30.0), (2.0, 20.0, 90.0)]:
        ws = Windshield(rate, glass_width_mm=1000.0, glass_height_mm=1000.0, glass_tilt_deg=tilt, car_speed_m_s=speed, wipers=0)
        lam = mp_slope(rate)
        a = math.radians(tilt)

        def integrand(d: float) -> float:
            v = float(physics.terminal_velocity(min(d, 8.0)))
            return MP_N0 * math.exp(-lam * d) * RHO_W * math.pi * (d * 1e-3) ** 3 / 6 * (v * math.cos(a) + speed * math.sin(a))

        want = integrate.quad(integrand, 0.0, 20.0, limit=200, points=[0.5, 6.0])[0]  # kg / m^2 / s
        out[f"{rate:g} mm/h, {speed:g} m/s, tilt {tilt:g}"] = ws.arrival_kg_per_s() / want
    return out


def item6(r: Renderer) -> dict[str, float]:
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0)
    scene = photo(cam)
    out = {}
    for rate, far in [(10.0, 2.0), (25.0, 2.0), (50.0, 2.0), (50.0, 3.0)]:
        means = {}
        for f in (None, far):
            w = Weather(rain_rate_mm_h=rate, rain_near_m=10.0, rain_far_m=f, rain_method="drops")
            means[f] = np.mean([r.render(scene, w, seed=s).layers["rain_alpha"].mean() for s in range(8)])
        out[f"{rate:g} mm/h, far {far:g} m of 10 m (8 seeds)"] = float(means[far] / means[None])
    return out


def measure() -> dict[str, dict[str, float]]:
    r = Renderer(W, H)
    return {
        "1. rain_alpha / (1 - exp(-beta L)), drops": item1(r),
        "2. billboards / drops": item2(r),
        "3. near rays": item3(r),
        "5. windshield arrival / full integral": item5(),
        "6. far LOD / per-drop": item6(r),
    }


def table(before: dict, after: dict) -> str:
    lines = ["| item | quantity | before | after |", "|---|---|---|---|"]
    for item, rows in after.items():
        for k, v in rows.items():
            b = before.get(item, {}).get(k)
            fmt = (lambda x: f"{x:.4f}") if 0.1 <= abs(v) < 10 else (lambda x: f"{x:.4g}")
            lines.append(f"| {item} | {k} | {fmt(b) if b is not None else '-'} | {fmt(v)} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--json")
    p.add_argument("--md", nargs=2)
    a = p.parse_args()
    if a.md:
        before, after = (json.loads(Path(x).read_text()) for x in a.md)
        sys.stdout.write(table(before, after))
        return
    got = measure()
    text = json.dumps(got, indent=1)
    if a.json:
        Path(a.json).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
