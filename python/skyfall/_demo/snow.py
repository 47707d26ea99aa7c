"""The demo's snow (``make demo``): the bundled street after an hour of snow in a light wind,
and a real photo with a measured depth map under snow.

- ``street_snow.png``: :func:`skyfall.scenes.street` after an hour of 4 mm/h (water
  equivalent; 4 cm of fresh snow at 100 kg/m^3) in a wind of 1.5 m/s along the street towards
  the camera and 0.3 m/s across it: the street white to the buildings' feet (below the roofs
  the wind is slowed by the canopy, and the snow's paths spread over the flakes' speeds and
  the gusts, so the shadows are short and soft) and a thinner stretch before the tall block
  closing the view, with the snow's edge lifted where it ends.
- ``photo_snow.png``: scikit-image's ``stereo_motorcycle`` (the left view of Middlebury's 2014
  *Motorcycle*, Scharstein et al., GCPR 2014) before and after 6 mm/h for an hour in still air:
  its depth from the bundled disparity through the dataset's calibration (f = 3979.911 px,
  baseline 193.001 mm, doffs 124.343 px at 2964 px wide; the image is a quarter of that),
  missing disparities filled from their nearest valid neighbour, and the camera's pitch
  (10.7 degrees down, 0.93 m up) from a plane fitted to the floor at the bottom of the image.
  The snow lies on the floor, the seat, the shelves and the box tops, not on the walls or the
  motorcycle's flanks. Needs scikit-image and scipy (``make demo`` installs them).

(An indoor photo under snow is odd, but it is the one photo at hand with a measured depth map.)
"""

from __future__ import annotations

from collections.abc import Callable
import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from skyfall import Camera, Frame, PhotoScene, Renderer, Weather, io, scenes, snow

__all__ = ["PHOTO_SNOW", "STREET_SNOW", "SnowDemo", "motorcycle", "write"]

# Middlebury 2014 Motorcycle's calibration, at the full 2964 px width.
_F_PX, _CX_PX, _CY_PX, _DOFFS_PX, _BASELINE_M, _FULL_W = 3979.911, 1244.772, 1019.507, 124.343, 0.193001, 2964


def motorcycle(width: int | None = None) -> PhotoScene:
    """scikit-image's stereo motorcycle (741 x 500) with its depth from the disparity (see the
    module docs), optionally resized to ``width`` px (the depth resampled to it, nearest)."""
    from scipy import ndimage  # type: ignore[import-untyped]
    from skimage import data

    left, _right, disp = data.stereo_motorcycle()  # type: ignore[no-untyped-call]
    ok = np.isfinite(disp)
    nearest = ndimage.distance_transform_edt(~ok, return_distances=False, return_indices=True)
    disp = disp[tuple(nearest)]
    h0, w0 = disp.shape
    scale = w0 / _FULL_W
    depth = (_F_PX * scale * _BASELINE_M / (disp + _DOFFS_PX * scale)).astype(np.float32)
    img = np.asarray(left, dtype=np.uint8)
    if width is not None and width != w0:
        from skyfall._demo.photo import _resized

        img = _resized(img, width)
        h, w = img.shape[:2]
        rows = np.minimum((np.arange(h) + 0.5) * h0 / h, h0 - 1).astype(int)
        cols = np.minimum((np.arange(w) + 0.5) * w0 / w, w0 - 1).astype(int)
        depth = np.ascontiguousarray(depth[rows][:, cols])
        scale = w / _FULL_W
    h, w = img.shape[:2]
    cam = Camera(
        (0.0, 0.93, 0.0), pitch_deg=-10.7, width=w, height=h, fx=_F_PX * scale, fy=_F_PX * scale, cx=_CX_PX * scale, cy=_CY_PX * scale
    )
    return PhotoScene(img, depth, camera=cam)


@dataclass(frozen=True)
class SnowDemo:
    """A scene under snow: the cover ``weather`` lays in ``duration_s``, then the frame."""

    name: str
    scene: Callable[[int | None], scenes.BoxScene | PhotoScene]
    """The scene, for a frame of a width (None: the demo's; a photo is resized to it)."""
    weather: Weather
    duration_s: float = 3600.0
    resolution_m: float = 0.25
    dt_s: float = 120.0
    seed: int = 0

    def cover(self, scene: scenes.BoxScene | PhotoScene) -> snow.SnowCover:
        return snow.accumulate(scene, self.weather, duration_s=self.duration_s, dt_s=self.dt_s, resolution_m=self.resolution_m, seed=self.seed)

    def render(self, width: int, height: int, backend: str = "cpu") -> tuple[Frame, Frame]:
        """(the scene without snow, with its cover), at ``width`` x ``height`` (a photo keeps
        its aspect: ``height`` is then its own)."""
        scene = self.scene(width)
        if isinstance(scene, PhotoScene):
            height, width = scene.shape
        r = Renderer(width, height, backend=backend)
        bare = r.render(scene, Weather(), seed=self.seed)
        return bare, r.render(scene, dataclasses.replace(self.weather, snow_cover=self.cover(scene)), seed=self.seed)


STREET_SNOW = SnowDemo("street_snow", lambda _w: scenes.street(), Weather(snow_rate_mm_h=4.0, wind_m_s=(0.3, 0.0, 1.5)))
"""The street after an hour of 4 mm/h in a light wind along it."""
PHOTO_SNOW = SnowDemo("photo_snow", motorcycle, Weather(snow_rate_mm_h=6.0), resolution_m=0.02, dt_s=300.0)
"""The motorcycle photo after an hour of 6 mm/h in still air (2 cm cells: the photo spans a
few metres)."""
SNOW_DEMOS = (STREET_SNOW, PHOTO_SNOW)


def png8(frame: Frame) -> NDArray[np.uint8]:
    """A frame's 8-bit sRGB pixels."""
    return io.to_srgb8(frame.rgb)


def write(out: Path, width: int = 1280, height: int = 720) -> list[Path]:
    """Render :data:`SNOW_DEMOS` into ``out``: the street with its cover, the photo before
    and after side by side; the files written."""
    street = out / "street_snow.png"
    _bare, snowy = STREET_SNOW.render(width, height)
    io.write_image(street, png8(snowy))
    photo = out / "photo_snow.png"
    before, after = PHOTO_SNOW.render(741, 500)
    io.write_image(photo, np.concatenate([png8(before), png8(after)], axis=1))
    return [street, photo]
