"""Weather inside your own tests: sweep rain rates over an image and check your model.

:func:`with_weather` puts weather on a uint8 image (a :class:`skyfall.PhotoScene`: without a
depth map its sky estimated and everything else 10 m away, rendered by
:meth:`skyfall.Renderer.render_srgb8`). The pytest plugin (:mod:`skyfall.pytest_plugin`,
loaded by pytest through the ``pytest11`` entry point) gives the session-scoped
``skyfall_renderer`` fixture, a :class:`RendererCache`.

Examples
--------
>>> import numpy as np
>>> image = np.full((36, 64, 3), 120, np.uint8)
>>> with_weather(image, rain_rate_mm_h=0.0).tobytes() == image.tobytes()  # clear: unchanged
True
>>> with_weather(image, rain_rate_mm_h=25.0, seed=1).shape
(36, 64, 3)
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import choice
from skyfall.render import BACKENDS, Renderer
from skyfall.scenes import PhotoScene
from skyfall.weather import Weather

__all__ = ["RENDERERS", "RendererCache", "with_weather"]


class RendererCache:
    """Renderers made on first use, one per size (a :class:`skyfall.Renderer` renders one
    size, and users' images come in many): ``cache(width, height)``.

    Parameters
    ----------
    backend : {"cpu", "gpu", "auto"}
        The renderers' backend. ``"cpu"`` (default), the reference, gives the same bytes on
        every machine and the fused 8-bit path for photos.

    Examples
    --------
    >>> cache = RendererCache()
    >>> cache(64, 36) is cache(64, 36), cache(64, 36).width
    (True, 64)
    """

    def __init__(self, backend: str = "cpu") -> None:
        self.backend = choice("backend", backend, BACKENDS)
        self._renderers: dict[tuple[int, int], Renderer] = {}
        self._lock = threading.Lock()

    def __call__(self, width: int, height: int) -> Renderer:
        """The renderer of ``width`` x ``height`` px (each in [1, 16384]), made once."""
        with self._lock:
            renderer = self._renderers.get((width, height))
            if renderer is None:
                renderer = Renderer(width, height, backend=self.backend)  # checks the size
                self._renderers[(width, height)] = renderer
            return renderer

    def for_image(self, image: Any) -> Renderer:
        """The renderer of an (H, W, ...) image's size."""
        shape = np.shape(image)
        if len(shape) < 2:
            raise ValueError(f"image must have shape (H, W, 3), got {shape}")
        return self(int(shape[1]), int(shape[0]))


RENDERERS = RendererCache()
"""The process's renderers on the CPU backend: what :func:`with_weather` uses by default and
the ``skyfall_renderer`` fixture gives."""


def with_weather(
    image_uint8: Any,
    *,
    rain_rate_mm_h: float = 0.0,
    depth_m: Any = None,
    seed: int = 0,
    time_s: float = 0.0,
    renderer: Renderer | None = None,
    scene_options: Mapping[str, Any] | None = None,
    **weather_fields: Any,
) -> NDArray[np.uint8]:
    """The image under weather, as uint8 sRGB: the augmentation one test case needs.

    Parameters
    ----------
    image_uint8 : ndarray of uint8, shape (H, W, 3)
        sRGB codes (the image your model reads).
    rain_rate_mm_h : float
        Rain rate, mm/h, in [0, 500]; 0 with no other weather gives the image back unchanged.
    depth_m : array_like, shape (H, W), optional
        Depth along the optical axis, m (``inf``: sky). Without it, :class:`skyfall.PhotoScene`'s
        model: the sky estimated from the pixels, everything else at ``distance_m`` (10 m;
        ``scene_options`` can set ``distance_m``, ``sky_mask``, or ``camera_height_m`` and
        ``horizon_row`` for a ground plane).
    seed : int
        Seed of the rain, in [0, 2^64): the same seed gives the same bytes.
    time_s : float
        Time of the frame, s, in [-1e7, 1e7] (the drops' positions).
    renderer : skyfall.Renderer, optional
        A renderer of the image's size (e.g. ``skyfall_renderer(w, h)``); by default one
        from :data:`RENDERERS` (CPU backend), made once per size.
    scene_options : mapping, optional
        More :class:`skyfall.PhotoScene` arguments (``camera``, ``vertical_fov_deg``,
        ``airlight``, ``camera_height_m``, ``horizon_row``, ...).
    **weather_fields
        More :class:`skyfall.Weather` fields: ``visibility_m``, ``wind_m_s``,
        ``rain_near_m``, ...

    Returns
    -------
    ndarray of uint8, shape (H, W, 3)
        A new image; ``image_uint8`` is not changed.

    Raises
    ------
    TypeError
        When ``image_uint8`` is not a uint8 array.
    ValueError
        When ``image_uint8`` is not (H, W, 3), a parameter is out of its range, or
        ``renderer`` is not the image's size.
    """
    image = np.asarray(image_uint8)
    if image.dtype != np.uint8:
        raise TypeError(f"image_uint8 must be a uint8 array of sRGB codes, got dtype {image.dtype}")
    if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] == 0 or image.shape[1] == 0:
        raise ValueError(f"image_uint8 must have shape (H, W, 3) with H, W >= 1, got {image.shape}")
    weather = Weather(rain_rate_mm_h=rain_rate_mm_h, **weather_fields)
    scene = PhotoScene(image, depth_m, **dict(scene_options or {}))
    r = renderer if renderer is not None else RENDERERS.for_image(image)
    if not isinstance(r, Renderer):
        raise TypeError(f"renderer must be a skyfall.Renderer, got {type(r).__name__}")
    return r.render_srgb8(scene, weather, seed=seed, time_s=time_s)
