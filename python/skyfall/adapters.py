"""skyfall inside the pipelines people already have: an albumentations transform.

``pip install 'skyfall[albumentations]'``. :class:`AlbumentationsWeather` is an
``ImageOnlyTransform`` over :func:`skyfall.augment`: any image size, uint8 or float images,
ranges drawn from the pipeline's own seed (``A.Compose([...], seed=...)`` gives the same
images every run), serialisable with ``A.to_dict`` / ``A.from_dict``, an optional ``depth``
target (metres, ``inf`` sky) and the ground-truth layers returned beside the image under their
names (``out["rain_alpha"]``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

try:
    from albumentations.core.transforms_interface import ImageOnlyTransform  # type: ignore[import-untyped]
except ImportError as exc:  # pragma: no cover - the message is the point
    raise ImportError("skyfall.adapters needs albumentations: pip install 'skyfall[albumentations]'") from exc

from skyfall.augmentation import augment

__all__ = ["AlbumentationsWeather"]

Range = float | tuple[float, float]


class AlbumentationsWeather(ImageOnlyTransform):  # type: ignore[misc]
    """Physically based weather as an albumentations transform.

    Each value may be a number or a range ``(lo, hi)`` drawn per image, as
    :func:`skyfall.augment` draws it (uniform; log-uniform for visibility and exposure), from a
    seed drawn from the transform's random generator (which ``A.Compose(seed=...)`` sets).

    Parameters
    ----------
    rain_rate_mm_h : float or (float, float)
        Rain rate, mm/h, in [0, 500] (default 1-50).
    snow_rate_mm_h : float or (float, float)
        Snowfall, water equivalent, mm/h, in [0, 100] (default 0).
    visibility_m : float or (float, float)
        Visibility of the air without the precipitation, m (default inf: clear air).
    wind_m_s : float or (float, float)
        Cross wind (x), m/s (default 0).
    exposure_s : float or (float, float)
        Shutter time, s, in [1e-6, 0.1] (default 1/30).
    rain_near_m : float
        Radius of the streak region, m (default 5).
    layers : sequence of str
        Ground-truth layers to return beside the image under their names (default
        ``("rain_alpha",)``; ``()`` for none): ``rain_alpha``, ``snow_alpha``, ``depth_m``,
        and with float frames ``transmittance`` and the others of :class:`skyfall.Frame`.
    backend : {"cpu", "gpu", "auto"}
        The renderers' backend (default ``"cpu"``).
    p : float
        Probability of applying the transform.

    Examples
    --------
    >>> import albumentations as A, numpy as np
    >>> pipe = A.Compose([AlbumentationsWeather(rain_rate_mm_h=(5.0, 40.0), p=1.0)], seed=7)
    >>> out = pipe(image=np.full((36, 64, 3), 90, np.uint8))
    >>> out["image"].shape, out["rain_alpha"].shape
    ((36, 64, 3), (36, 64))
    """

    def __init__(
        self,
        rain_rate_mm_h: Range = (1.0, 50.0),
        snow_rate_mm_h: Range = 0.0,
        visibility_m: Range = math.inf,
        wind_m_s: Range = 0.0,
        exposure_s: Range = 1.0 / 30.0,
        rain_near_m: float = 5.0,
        layers: Sequence[str] = ("rain_alpha",),
        backend: str = "cpu",
        p: float = 1.0,
    ) -> None:
        super().__init__(p=p)
        self.rain_rate_mm_h = _value(rain_rate_mm_h)
        self.snow_rate_mm_h = _value(snow_rate_mm_h)
        self.visibility_m = _value(visibility_m)
        self.wind_m_s = _value(wind_m_s)
        self.exposure_s = _value(exposure_s)
        self.rain_near_m = float(rain_near_m)
        self.layers = tuple(layers)
        self.backend = backend
        self._last: dict[str, NDArray[Any]] = {}

    @property
    def targets(self) -> dict[str, Callable[..., Any]]:
        """``image`` (and ``images``), and ``depth``: the image's depth map, passed through."""
        return {"image": self.apply, "images": self.apply_to_images, "depth": self.apply_to_depth}

    def get_params(self) -> dict[str, Any]:
        """The seed of this call, from the transform's generator (set by ``Compose(seed=...)``)."""
        return {"weather_seed": int(self.random_generator.integers(0, 2**63))}

    def get_params_dependent_on_data(self, params: dict[str, Any], data: dict[str, Any]) -> dict[str, Any]:
        """The ``depth`` target, when given, for the image's scene."""
        return {"scene_depth_m": data.get("depth")}

    def _fields(self) -> dict[str, Any]:
        wind = self.wind_m_s
        return {
            "rain_rate_mm_h": self.rain_rate_mm_h,
            "snow_rate_mm_h": self.snow_rate_mm_h,
            "visibility_m": self.visibility_m,
            "wind_m_s": wind if isinstance(wind, tuple) else (float(wind), 0.0, 0.0),
            "exposure_s": self.exposure_s,
            "rain_near_m": self.rain_near_m,
        }

    def apply(self, img: NDArray[Any], weather_seed: int = 0, scene_depth_m: Any = None, **params: Any) -> NDArray[Any]:
        """The image with weather (its layers kept for :meth:`apply_with_params`)."""
        encoding = None if img.dtype == np.uint8 else "srgb"  # albumentations' floats: [0, 1]
        out, layers = augment(
            img, seed=weather_seed, depth_m=scene_depth_m, encoding=encoding, return_layers=True, backend=self.backend, **self._fields()
        )
        self._last = dict(layers)
        result: NDArray[Any] = out
        return result

    def apply_to_depth(self, depth: NDArray[Any], **params: Any) -> NDArray[Any]:
        """The depth map, unchanged."""
        return depth

    def apply_with_params(self, params: dict[str, Any], *args: Any, **kwargs: Any) -> dict[str, Any]:
        """albumentations' application, with the asked-for layers added under their names."""
        self._last = {}
        res: dict[str, Any] = super().apply_with_params(params, *args, **kwargs)
        for name in self.layers:
            if name in self._last:
                res[name] = self._last[name]
            elif "image" in kwargs:
                h, w = np.shape(kwargs["image"])[:2]
                res[name] = np.zeros((h, w), np.float32)  # a layer the frame did not draw: none of it
        return res

    def get_transform_init_args_names(self) -> tuple[str, ...]:
        """The arguments ``A.to_dict`` records."""
        return ("rain_rate_mm_h", "snow_rate_mm_h", "visibility_m", "wind_m_s", "exposure_s", "rain_near_m", "layers", "backend")


def _value(v: Any) -> Range:
    """A number, or a range as a tuple (``A.from_dict`` gives lists back)."""
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"a range is (lo, hi), got {v!r}")
        return (float(v[0]), float(v[1]))
    return float(v)
