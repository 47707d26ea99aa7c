"""The demo's real photos in the rain (``make demo``): scikit-image's ``rocket`` at dusk and
its ``astronaut``, through the 8-bit augmentation path.

The rocket is a dusk sky over a launch pad. Its depth map is made here, by hand, and stated:
the sky by colour (blue over red, cleaned by a morphological opening) at ``inf``, the two near
towers 60 m away, the rocket and its masts 250 m, the pad 150 m. The sky is then hazed up to
the cloud base and the towers by their distance, towards the photo's own airlight (its
horizon sky), so the dusk stays dusk: before, any rain at all made that sky flat grey
(175, 175, 175). At dusk the drops themselves are dim (they are lit by that sky): the rain
shows as mist. The astronaut is a bright portrait 4 m away (a constant depth map), where the
streaks show. Both need scikit-image and scipy (``make demo`` installs them).

The wet photo is the bundled street, rendered dry and saved as an 8-bit photo with its depth
map (what a user brings from a dashcam and a depth estimator), then wetted through the photo
path: the road darkens and mirrors the photo's own buildings and sky by a march through its
depth map, the pavement under the awning stays dry (the awning is among its ``occluders``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes

__all__ = ["PHOTO_FRAMES", "PhotoFrame", "astronaut", "rocket", "street_photo"]


def _resized(image: NDArray[np.uint8], width: int | None) -> NDArray[np.uint8]:
    if width is None or width == image.shape[1]:
        return image
    from skimage import transform

    height = round(image.shape[0] * width / image.shape[1])
    small = np.asarray(transform.resize(image, (height, width), anti_aliasing=True), dtype=np.float64)  # type: ignore[no-untyped-call]
    return np.round(small * 255).astype(np.uint8)


def rocket(width: int | None = None) -> PhotoScene:
    """scikit-image's rocket (640 x 427) at dusk with the made depth map above, optionally
    resized to ``width`` px; a camera 1.6 m up, pitched 18 degrees, 50 degrees of view."""
    from scipy import ndimage  # type: ignore[import-untyped]
    from skimage import data

    img = _resized(np.asarray(data.rocket(), dtype=np.uint8), width)  # type: ignore[no-untyped-call]
    h, w = img.shape[:2]
    c = img.astype(int)
    sky = ndimage.binary_opening((c[..., 2] > 1.25 * c[..., 0] + 8) & (c[..., 2] > 35))
    rows, cols = np.mgrid[0:h, 0:w]
    depth = np.where((cols < 0.14 * w) | (cols > 0.875 * w), 60.0, 250.0)
    depth = np.where(rows >= 0.95 * h, 150.0, depth)
    depth = np.where(sky, np.inf, depth).astype(np.float32)
    cam = Camera((0.0, 1.6, 0.0), pitch_deg=18.0, vertical_fov_deg=50.0)
    return PhotoScene(img, depth, camera=cam)


def astronaut(width: int | None = None) -> PhotoScene:
    """scikit-image's astronaut (512 x 512), 4 m from a level camera with 40 degrees of view
    and a 1/60 s exposure, optionally resized to ``width`` px."""
    from skimage import data

    img = _resized(np.asarray(data.astronaut(), dtype=np.uint8), width)  # type: ignore[no-untyped-call]
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=40.0, exposure_s=1.0 / 60.0)
    return PhotoScene(img, np.full(img.shape[:2], 4.0, np.float32), camera=cam)


def street_photo(width: int | None = None) -> PhotoScene:
    """The bundled street rendered dry (16:9, ``width`` px wide, 640 by default) as an 8-bit
    photo with its depth map, its camera, and its boxes as the photo's ``occluders``."""
    w = 640 if width is None else width
    h = w * 9 // 16
    street = scenes.street()
    clear = Renderer(w, h, backend="cpu").render(street)
    occluders = [{"min": tuple(b[:3]), "max": tuple(b[3:6])} for b in np.asarray(street.boxes, dtype=float)]
    return PhotoScene(io.to_srgb8(clear.rgb), clear.depth_m, camera=street.camera, occluders=occluders)


@dataclass(frozen=True)
class PhotoFrame:
    """A photo of the demo in the rain: ``{name}.png`` shows it before and after, side by side."""

    name: str
    photo: Callable[[int | None], PhotoScene]
    """The scene at a width (None: the photo's own)."""
    weather: Weather
    seed: int = 1

    def scene(self, width: int | None = None) -> PhotoScene:
        return self.photo(width)

    def render(self, width: int | None = None) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
        """(the photo, the photo in the rain), 8-bit sRGB."""
        scene = self.scene(width)
        h, w = scene.shape
        assert scene.srgb8 is not None
        return scene.srgb8, Renderer(w, h, backend="cpu").render_srgb8(scene, self.weather, seed=self.seed)


PHOTO_FRAMES = (
    PhotoFrame("photo_rain", rocket, Weather(rain_rate_mm_h=15.0)),
    PhotoFrame("photo_rain_portrait", astronaut, Weather(rain_rate_mm_h=25.0)),
    PhotoFrame("photo_wet", street_photo, Weather(rain_rate_mm_h=5.0, rain_duration_s=None)),
)
"""The rocket at dusk in 15 mm/h rain, the astronaut in 25 mm/h, the street photo wet in
5 mm/h."""


def write(out: Path) -> list[Path]:
    """Render :data:`PHOTO_FRAMES` at full size into ``out``; the files written."""
    paths = []
    for frame in PHOTO_FRAMES:
        before, after = frame.render()
        path = out / f"{frame.name}.png"
        io.write_image(path, np.concatenate([before, after], axis=1))
        paths.append(path)
    return paths
