"""The bundled demo: ``python -m skyfall._demo --out out`` (what ``make demo`` and ``skyfall demo``
run). Private: the demo's scenes, photos and plots are not part of the API.

Writes
------
rain_textures.exr
    Yoshida, Dobashi & Yamamoto's 4 x 6 rain-texture grid (R in {1, 5, 10, 20} mm/h, D in
    {1.0, ..., 2.0} mm, 512 px each) as a float32 atlas with its rates and diameters.
rain_textures.png
    A labelled contact sheet of the same grid.
terminal_velocity.png
    The three fall-speed models against Gunn & Kinzer's measurements, with relative error.
street.exr, street.png
    The bundled street scene at 1280 x 720 in 10 mm/h rain haze (EXR: rgb, depth_m and the
    transmittance layer; PNG: 8-bit sRGB).
street_rain_day.exr, street_rain_day.png, street_rain_day_alpha.png
    The street by day in 50 mm/h rain with a 3 m/s cross wind: streaks of every drop within 5 m,
    and the rain_alpha ground-truth layer (stretched for viewing). Drops under the awning
    on the right see less sky and are dimmer (the ambient-light map, Yamamoto & Tadamura).
ambient_light.png
    The street's ambient-light map in that rain: horizontal sky illuminance 1.5 m up, and a
    section across the street 20 m ahead showing the awning's shade.
street_rain.exr, street_rain.png
    The rainy street at dusk (30 lx of sky) in 20 mm/h rain with its lamps lit and an oncoming
    car's headlights: the lamps light pools on the street and the walls (the awning shades the
    pavement beneath it), the car's beams light the road and the drops, and every lamp and
    headlight in view shows as a small emitter with its glow through the rain (the PNG saved at
    exposure 0.1).
windshield.png, windshield.mp4
    The in-car view (:mod:`skyfall.windshield`, Gotou, Tanaka & Sagawa): the street in 10 mm/h
    rain through a windshield a minute into the rain, its two wipers mid-sweep, the drops
    refracting the street; and 3 s of the wipers at 24 fps, 640 x 360 (the video extra).
photo_rain.png, photo_rain_portrait.png
    Real photos through the 8-bit path, before and after (:mod:`skyfall._demo.photo`):
    scikit-image's rocket at dusk in 15 mm/h rain with a made depth map (the sky keeps its
    dusk, the towers fade into the photo's own airlight), its astronaut in 25 mm/h.
street_clouds.exr, street_clouds.png
    The street under a broken cloud field (:mod:`skyfall.clouds`, Shimada, Shinya, Shiraishi &
    Harada) in a clear sky with the sun behind the camera: the clouds lit through their
    attenuation volume, and their shadow on the sunlit facade and the far street
    (``sun_transmittance``).
street_snow.png, photo_snow.png
    The street after an hour of snow in a light wind along it (bare in the lee of the
    buildings), and a photo with a measured depth map under snow, before and after
    (:mod:`skyfall._demo.snow`).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from skyfall import Camera, Frame, Renderer, Weather, io, physics, rain, scenes, sky
from skyfall._reference import gunn_kinzer_1949

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class DemoFrame:
    """One of the demo's street frames: what it shows, in what weather, and how its PNG is saved."""

    name: str
    """File stem: ``{name}.exr`` and ``{name}.png``."""
    scene: Callable[[], scenes.BoxScene]
    weather: Weather
    seed: int = 0
    exposure: float = 1.0
    """Multiplier of the linear frame before the PNG's sRGB encoding."""
    camera: Callable[[], Camera] | None = None
    """The camera, when not the scene's own."""

    def render(self, renderer: Renderer) -> Frame:
        cam = None if self.camera is None else self.camera()
        return renderer.render(self.scene(), self.weather, seed=self.seed, camera=cam)

    def png8(self, frame: Frame) -> NDArray[np.uint8]:
        """The frame's 8-bit sRGB PNG pixels, as :meth:`skyfall.Frame.save` writes them."""
        return io.to_srgb8(frame.rgb * np.float32(self.exposure))


STREET = DemoFrame("street", scenes.street, Weather(rain_rate_mm_h=10.0))
"""The street in 10 mm/h rain haze (and its streaks)."""
STREET_RAIN_DAY = DemoFrame("street_rain_day", scenes.street, Weather(rain_rate_mm_h=50.0, wind_m_s=(3.0, 0.0, 0.0)))
"""The street by day in 50 mm/h rain with a 3 m/s cross wind."""
STREET_RAIN_DUSK = DemoFrame(
    "street_rain",
    partial(scenes.street, lamps=True, headlights=True),
    Weather(rain_rate_mm_h=20.0, sky_illuminance_lux=30.0),
    exposure=0.1,
)
"""The street at dusk (30 lx of sky) in 20 mm/h rain, lamps lit and a car's headlights on."""
STREET_CLOUDS = DemoFrame(
    "street_clouds",
    scenes.street,
    Weather(sky=12, sun_elevation_deg=50.0, sun_azimuth_deg=185.0, clouds="broken", visibility_m=20_000.0),
    exposure=0.2,
    camera=partial(Camera, (1.5, 1.6, 0.0), pitch_deg=8.0),
)
"""The street under a broken cloud field (:data:`skyfall.clouds.PRESETS`) in a clear sky, the
sun 50 deg up in the south behind the camera: a cloud's shadow lies over the near street, the
far street and the buildings at its end are in the sun (the PNG saved at exposure 0.2: the
sun's light is about nine times the sky's)."""
STREET_WET = DemoFrame(
    "street_wet",
    partial(scenes.street, lamps=True, headlights=True),
    Weather(rain_rate_mm_h=5.0, sky_illuminance_lux=30.0, rain_duration_s=None),
    exposure=0.1,
)
"""The street at dusk after enough 5 mm/h rain to wet it (:mod:`skyfall.wet`): the road darker,
mirroring the buildings and the sky, the lamps' and the headlights' highlights streaked along
it, and the pavement under the awning dry."""
DEMO_FRAMES = (STREET, STREET_RAIN_DAY, STREET_RAIN_DUSK, STREET_CLOUDS, STREET_WET)
"""The demo's street frames (rendered at 1280 x 720; tests/test_golden.py at 320 x 180)."""


WINDSHIELD_PRESET = "rain"
"""The in-car view's windshield (:data:`skyfall.windshield.PRESETS`)."""
WINDSHIELD_TIME_S = 60.0 + 1.5 / 4
"""A minute into the rain, the wipers a quarter period into their sweep: mid-way, going up."""
WINDSHIELD_WEATHER = Weather(rain_rate_mm_h=10.0, visibility_m=2000.0, windshield=WINDSHIELD_PRESET)
"""10 mm/h on the street, seen through the windshield of a car driving in it."""


def windshield_camera() -> Camera:
    """The driver's eye: 1.3 m up in the street, an f/8 lens focused 10 m ahead (so the
    drops on the glass are out of focus, as a dashboard camera sees them)."""
    return Camera((1.5, 1.3, 0.0), pitch_deg=2.0, vertical_fov_deg=55.0, f_number=8.0, focus_distance_m=10.0)


def windshield_still(renderer: Renderer) -> Frame:
    """The in-car view: the street through a rainy windshield, the wipers mid-sweep."""
    return renderer.render(scenes.street(), WINDSHIELD_WEATHER, camera=windshield_camera(), time_s=WINDSHIELD_TIME_S, seed=0)


def windshield_clip(out: Path, width: int = 640, height: int = 360, seconds: float = 3.0, fps: int = 24) -> Path:
    """A wiper clip: the street in 10 mm/h rain through the ``"rain"`` preset's windshield, frame
    k at ``WINDSHIELD_TIME_S + k / fps`` (the preset's glass on the frames' clock,
    :func:`skyfall.windshield.clock`: the drops arrive, slide and are swept from frame to
    frame); H.264 through :func:`skyfall.video.write_video`."""
    from skyfall import video

    renderer = Renderer(width, height)
    frames = [
        io.to_srgb8(f.rgb)
        for f in renderer.render_sequence(
            scenes.street(), WINDSHIELD_WEATHER, n_frames=int(seconds * fps), fps=fps, camera=windshield_camera(), start_s=WINDSHIELD_TIME_S, seed=0
        )
    ]
    path = out / "windshield.mp4"
    video.write_video(path, frames, fps=fps)
    return path


def rain_alpha_png(frame: Frame) -> NDArray[np.float32]:
    """The rain_alpha layer stretched to its maximum for viewing (linear, [0, 1])."""
    alpha = frame.layers["rain_alpha"]
    stretched: NDArray[np.float32] = np.clip(alpha / np.float32(max(float(alpha.max()), 1e-6)), 0, 1)
    return stretched


def contact_sheet(tex: np.ndarray, rates: Sequence[float], diams: Sequence[float]) -> Figure:
    """A labelled grid of textures; each panel is stretched to its own 99.9th percentile."""
    from matplotlib.figure import Figure

    nr, nd = tex.shape[:2]
    fig = Figure(figsize=(2.2 * nd, 2.35 * nr))
    axes = fig.subplots(nr, nd, squeeze=False)
    for i in range(nr):
        for j in range(nd):
            t = tex[i, j]
            nz = t[t > 0]
            hi = float(np.percentile(nz, 99.9)) if nz.size else 1.0
            ax = axes[i, j]
            ax.imshow(t, cmap="gray", vmin=0.0, vmax=hi, interpolation="antialiased")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"R={rates[i]:g} mm/h D={diams[j]:.1f} mm\nmean {t.mean():.2e}, max {t.max():.3f}", fontsize=7)
    fig.suptitle("skyfall rain textures: 1 m cube, 1/30 s exposure (each panel stretched to its own range)", fontsize=9)
    fig.tight_layout()
    return fig


def velocity_plot() -> Figure:
    """The fall-speed models against Gunn & Kinzer 1949, with relative error."""
    from matplotlib.figure import Figure

    d_gk, v_gk = gunn_kinzer_1949()
    d = np.linspace(0.0, 8.0, 801)
    fig = Figure(figsize=(7, 7))
    ax, ax_err = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    ax.plot(d_gk, v_gk, "ko", ms=4, label="Gunn & Kinzer 1949 (measured)")
    for model in physics.FALL_SPEED_MODELS:
        ax.plot(d, physics.terminal_velocity(d, model=model), label=model)
        err = (np.asarray(physics.terminal_velocity(d_gk, model=model)) - v_gk) / v_gk * 100
        ax_err.plot(d_gk, err, ".-", label=model)
    ax.set_ylabel("fall speed (m/s)")
    ax.set_title("Raindrop terminal velocity, 20 °C, 1013.25 hPa, 50 % RH")
    ax.legend()
    ax.grid(alpha=0.3)
    ax_err.axhline(0, color="k", lw=0.5)
    ax_err.set_ylim(-15, 35)
    ax_err.set_xlabel("drop diameter (mm)")
    ax_err.set_ylabel("error vs G&K (%)")
    ax_err.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def ambient_plot(weather: Weather) -> Figure:
    """The street's ambient-light map: a plan at 1.5 m and a section across the street."""
    from matplotlib.figure import Figure

    amb = sky.ambient_light_map(scenes.street(), spacing_m=1.0, weather=weather)
    g = np.where(amb.solid, np.nan, amb.grid[..., 0])  # nodes inside boxes: blank (grey)
    o, s = amb.origin_m, amb.spacing_m
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2, width_ratios=[2.2, 1])
    for ax in (ax1, ax2):
        ax.set_facecolor("0.6")
    j = int(round((1.5 - o[1]) / s))
    x_ext = (o[0], o[0] + s * (g.shape[0] - 1))
    im = ax1.imshow(g[:, j, :], origin="lower", aspect="auto", extent=(o[2], o[2] + s * (g.shape[2] - 1), *x_ext), vmin=0, vmax=weather.sky_illuminance_lux)
    ax1.set(xlabel="z, m (the camera at 0 looks towards -z)", ylabel="x, m", title="sky illuminance on a horizontal surface 1.5 m up", ylim=(-9, 9))
    k = int(round((-20.0 - o[2]) / s))
    ax2.imshow(g[:, :, k].T, origin="lower", aspect="auto", extent=(*x_ext, o[1], o[1] + s * (g.shape[1] - 1)), vmin=0, vmax=weather.sky_illuminance_lux)
    ax2.set(xlabel="x, m", ylabel="y, m", title="section across the street, z = -20 m", xlim=(-9, 9), ylim=(0, 12))
    fig.colorbar(im, ax=[ax1, ax2], label="lux")
    return fig


def main(argv: list[str] | None = None) -> int:
    """Render the demo outputs into ``--out``."""
    parser = argparse.ArgumentParser(prog="python -m skyfall._demo", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder (created)")
    args = parser.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)

    rates, diams = rain.SEED_RAIN_RATES_MM_H, rain.SEED_DIAMETERS_MM
    t0 = time.perf_counter()
    tex = rain.textures(rates, diams, size_px=512, seed=0)
    dt = time.perf_counter() - t0
    print(f"rain textures: {tex.shape[0]} x {tex.shape[1]} of 512 px in {dt * 1e3:.1f} ms (Yoshida, Dobashi & Yamamoto: 164 s)")
    rain.write_atlas(out / "rain_textures.exr", tex, rates, diams)
    contact_sheet(tex, rates, diams).savefig(out / "rain_textures.png", dpi=110)
    velocity_plot().savefig(out / "terminal_velocity.png", dpi=110)
    renderer = Renderer(1280, 720)
    frames: dict[str, Frame] = {}
    for demo in DEMO_FRAMES:
        t0 = time.perf_counter()
        frames[demo.name] = frame = demo.render(renderer)
        dt = time.perf_counter() - t0
        print(f"{demo.name}, {demo.weather.rain_rate_mm_h:g} mm/h: 1280x720 on the {renderer.backend} backend in {dt * 1e3:.1f} ms, {frame.stats.get('rain_streaks', 0)} streaks")
        frame.save(out / f"{demo.name}.exr")
        frame.save(out / f"{demo.name}.png", exposure=demo.exposure)
    wet_weather = STREET_RAIN_DAY.weather
    e = sky.ambient_light_map(scenes.street(), weather=wet_weather).sample([[5.5, 1.5, -3.0], [0.0, 1.5, -3.0]])
    print(f"sky light on a drop under the awning: {e[0] / e[1]:.0%} of one in the middle of the street")
    ambient_plot(wet_weather).savefig(out / "ambient_light.png", dpi=100)
    io.write_image(out / "street_rain_day_alpha.png", rain_alpha_png(frames[STREET_RAIN_DAY.name]))
    t0 = time.perf_counter()
    still = windshield_still(renderer)
    dt = time.perf_counter() - t0
    print(f"windshield ({WINDSHIELD_PRESET}), the wipers mid-sweep: 1280x720 in {dt * 1e3:.1f} ms (with the glass's warm-up, then cached for the clip)")
    still.save(out / "windshield.png")
    windshield_files = ["windshield.png"]
    try:
        windshield_files.append(windshield_clip(out).name)
    except ImportError as e:  # PyAV is the video extra
        print(f"no windshield clip: {e}")
    from skyfall._demo import photo as demo_photo

    photos = demo_photo.write(out)
    from skyfall._demo import snow as demo_snow

    photos += demo_snow.write(out)
    names = ["rain_textures.exr", "rain_textures.png", "terminal_velocity.png", "street_rain_day_alpha.png", "ambient_light.png"]
    names += [f"{d.name}.{ext}" for d in DEMO_FRAMES for ext in ("exr", "png")]
    for name in names:
        print(f"wrote {out / name}")
    for name in windshield_files:
        print(f"wrote {out / name}")
    for path in photos:
        print(f"wrote {path}")
    return 0

