"""Image in, image out: weather on any photo of any size in one call, with its ground truth.

:func:`augment` is what a training pipeline or a one-line test wants: the same dtype and shape
back, any size (renderers are cached by size), ranges drawn from a seed, and the layers when
asked. It builds a :class:`skyfall.PhotoScene` of each image (the photo scene model: with no
depth map, the sky estimated and the rest 10 m away, so no content is lost) and renders it
with :meth:`skyfall.Renderer.render_srgb8` (uint8) or :meth:`skyfall.Renderer.render` (floats).
:class:`skyfall.adapters.AlbumentationsWeather` is the same inside ``A.Compose``.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections import OrderedDict
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import integer
from skyfall.camera import Camera
from skyfall.io import encode_srgb
from skyfall.photo_scene import PhotoScene
from skyfall.render import Renderer
from skyfall.sky_mask import check_encoding
from skyfall.weather import Weather

__all__ = ["CAMERA_FIELDS", "LOG_UNIFORM", "MAX_RENDERERS", "Layers", "augment", "draw"]

CAMERA_FIELDS = ("exposure_s", "f_number", "focus_distance_m", "vertical_fov_deg")
"""The :class:`skyfall.Camera` fields :func:`augment` takes beside the weather's."""
LOG_UNIFORM = frozenset({"visibility_m", "sky_illuminance_lux", "exposure_s", "f_number", "focus_distance_m", "sun_illuminance_lux"})
"""Fields whose ranges are drawn log-uniformly (as the dataset command draws them); every other
range is uniform."""
MAX_RENDERERS = 8
"""How many renderers (one per image size and backend) :func:`augment` keeps, least recently
used dropped first."""

_RENDERERS: OrderedDict[tuple[int, int, str], Renderer] = OrderedDict()


class Layers(dict[str, NDArray[Any]]):
    """The ground truth of an augmented image: each layer by name (``rain_alpha``,
    ``snow_alpha``, ``transmittance``, ``depth_m``, ...), and in :attr:`params` what was drawn
    (every field given as a range, its value) and the seed used."""

    params: dict[str, Any]

    def __init__(self, layers: dict[str, NDArray[Any]], params: dict[str, Any]) -> None:
        super().__init__(layers)
        self.params = params


def _renderer(width: int, height: int, backend: str) -> Renderer:
    key = (width, height, backend)
    r = _RENDERERS.get(key)
    if r is None:
        r = Renderer(width, height, backend=backend)
        _RENDERERS[key] = r
        while len(_RENDERERS) > MAX_RENDERERS:
            _RENDERERS.popitem(last=False)
    else:
        _RENDERERS.move_to_end(key)
    return r


def _is_range(value: Any) -> bool:
    return isinstance(value, (tuple, list)) and len(value) == 2 and all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in value)


def draw(fields: dict[str, Any], seed: int) -> dict[str, Any]:
    """Each field given as a range ``(lo, hi)`` drawn from ``seed`` alone; other values kept.

    Ranges are drawn in the fields' name order from ``numpy.random.default_rng(seed)``:
    log-uniform for :data:`LOG_UNIFORM`, uniform otherwise; ``wind_m_s`` as a pair is the cross
    wind (x) and becomes ``(x, 0, 0)``. ``lo == hi`` is that value.

    Examples
    --------
    >>> d = draw({"rain_rate_mm_h": (1.0, 50.0), "visibility_m": 300.0}, seed=3)
    >>> 1.0 <= d["rain_rate_mm_h"] <= 50.0, d["visibility_m"]
    (True, 300.0)
    """
    rng = np.random.default_rng(integer("seed", seed, 0, 2**64 - 1))
    out = dict(fields)
    for name in sorted(fields):
        v = fields[name]
        if not _is_range(v):
            continue
        lo, hi = float(v[0]), float(v[1])
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
            raise ValueError(f"{name} = ({v[0]}, {v[1]}): a range is two finite numbers lo <= hi")
        if name in LOG_UNIFORM:
            if lo <= 0.0:
                raise ValueError(f"{name} = ({v[0]}, {v[1]}) is drawn log-uniformly: both ends must be > 0")
            x = float(math.exp(rng.uniform(math.log(lo), math.log(hi)))) if hi > lo else lo
        else:
            x = float(rng.uniform(lo, hi)) if hi > lo else lo
        out[name] = (x, 0.0, 0.0) if name == "wind_m_s" else x
    return out


def _scene(rgb: NDArray[Any], depth_m: Any, camera: Camera | None, changes: dict[str, Any], encoding: str | None) -> PhotoScene:
    """The image's photo scene, its camera (the given one or the scene model's) with ``changes``."""
    scene = PhotoScene(rgb, depth_m, camera=camera, encoding=encoding)
    if not changes:
        return scene
    return PhotoScene(rgb, scene.depth_m, camera=scene.camera.replaced(**changes), encoding=encoding)


def _one(
    image: NDArray[Any],
    seed: int,
    depth_m: Any,
    camera: Camera | None,
    encoding: str | None,
    return_layers: bool,
    base: Weather,
    fields: dict[str, Any],
    backend: str,
) -> tuple[NDArray[Any], Layers | None]:
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise ValueError(f"image must have shape (H, W, 3) or (H, W, 4), a batch (N, H, W, C) or a list of them, got {image.shape}")
    drawn = draw(fields, seed)
    cam_changes = {k: drawn.pop(k) for k in CAMERA_FIELDS if k in drawn}
    weather = dataclasses.replace(base, **drawn) if drawn else base
    rgb = image[..., :3]
    h, w = rgb.shape[:2]
    r = _renderer(w, h, backend)
    if image.dtype == np.uint8:
        if encoding not in (None, "srgb"):
            raise ValueError("encoding = 'linear' does not fit a uint8 image: 8-bit images are sRGB codes")
        scene = _scene(np.ascontiguousarray(rgb), depth_m, camera, cam_changes, None)
        fused = ("rain_alpha", "snow_alpha") if weather.snow_rate_mm_h > 0 else ("rain_alpha",)
        layers: dict[str, NDArray[Any]] = {}
        if return_layers and not r.fuses_srgb8(scene, weather):
            frame = r.render(scene, weather, seed=seed)
            from skyfall.io import to_srgb8

            out_rgb: NDArray[Any] = to_srgb8(frame.rgb)
            layers = {**frame.layers, "depth_m": frame.depth_m}
        elif return_layers:
            out_rgb, fused_layers = r.render_srgb8(scene, weather, seed=seed, layers=fused)
            layers = {**fused_layers, "depth_m": scene.depth_m}
        else:
            out_rgb = r.render_srgb8(scene, weather, seed=seed)
    elif image.dtype.kind == "f":
        if encoding not in ("srgb", "linear"):
            raise ValueError(f"image is {image.dtype}: say how it is encoded, encoding='srgb' (values in [0, 1]) or encoding='linear'")
        scene = _scene(rgb, depth_m, camera, cam_changes, encoding)
        frame = r.render(scene, weather, seed=seed)
        out_rgb = np.clip(encode_srgb(frame.rgb), 0.0, 1.0) if encoding == "srgb" else frame.rgb
        out_rgb = out_rgb.astype(image.dtype, copy=False)
        layers = {**frame.layers, "depth_m": frame.depth_m}
    else:
        raise TypeError(f"image must be uint8 (sRGB codes) or float, got dtype {image.dtype}")
    if image.shape[2] == 4:  # the alpha passes through unchanged
        out = np.empty_like(image)
        out[..., :3] = out_rgb
        out[..., 3] = image[..., 3]
    else:
        out = np.asarray(out_rgb, dtype=image.dtype)
    if not return_layers:
        return out, None
    params = {**{k: v for k, v in drawn.items() if _is_range(fields.get(k))}, **{k: v for k, v in cam_changes.items() if _is_range(fields.get(k))}}
    params["seed"] = seed
    return out, Layers(layers, params)


def augment(
    image: Any,
    *,
    seed: int = 0,
    depth_m: Any = None,
    camera: Camera | None = None,
    encoding: str | None = None,
    return_layers: bool = False,
    weather: Weather | None = None,
    backend: str = "cpu",
    **fields: Any,
) -> Any:
    """Put weather on an image (or a batch, or a list of images of any sizes): image in, image out.

    Parameters
    ----------
    image : array_like or list of array_like
        uint8 sRGB codes (H, W, 3) or (H, W, 4) (the alpha passes through unchanged); floats
        with ``encoding``; a batch (N, H, W, C); or a list of images of different sizes.
    seed : int
        In [0, 2^64). Image k of a batch or a list uses ``seed + k``; every range is drawn
        from the image's seed alone (:func:`draw`), and its rain is seeded by it too.
    depth_m : array_like, optional
        The photo's depth map (m, ``inf`` sky, ``NaN`` no data), for a single image; without
        it :class:`skyfall.PhotoScene`'s model (the sky estimated, the rest 10 m away).
    camera : Camera, optional
        The camera that took it (default: the photo scene model's).
    encoding : {"srgb", "linear"}, optional
        How float pixels are encoded (required for floats); the result keeps it.
    return_layers : bool
        Also return the ground truth: ``(image, layers)``, a :class:`Layers` per image (a
        list for a batch or a list).
    weather : Weather, optional
        The weather to start from (default ``Weather()``); ``fields`` override it.
    backend : {"cpu", "gpu", "auto"}
        The renderers' backend (default ``"cpu"``: the same bytes on every machine).
    **fields
        :class:`skyfall.Weather` fields (``rain_rate_mm_h=25.0``, ``visibility_m=...``) and the
        camera's :data:`CAMERA_FIELDS` (``exposure_s=...``), each a value or a range
        ``(lo, hi)`` drawn per image (uniform, log-uniform for :data:`LOG_UNIFORM`;
        ``wind_m_s`` as a pair is the cross wind's range).

    Returns
    -------
    ndarray or list, and with ``return_layers`` the layers
        The same dtype and shape as ``image``.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.full((36, 64, 3), 90, np.uint8)
    >>> wet = augment(img, rain_rate_mm_h=25.0, seed=1)
    >>> wet.shape, wet.dtype
    ((36, 64, 3), dtype('uint8'))
    >>> wet, layers = augment(img, rain_rate_mm_h=(1.0, 50.0), seed=1, return_layers=True)
    >>> sorted(layers), 1.0 <= layers.params["rain_rate_mm_h"] <= 50.0
    (['depth_m', 'rain_alpha'], True)
    """
    check_encoding(encoding)
    base = Weather() if weather is None else weather
    if not isinstance(base, Weather):
        raise TypeError(f"weather must be a skyfall.Weather, got {type(base).__name__}")
    allowed = {f.name for f in dataclasses.fields(Weather)} | set(CAMERA_FIELDS)
    unknown = sorted(set(fields) - allowed)
    if unknown:
        raise TypeError(f"augment() got unknown weather or camera fields {unknown}; the fields are Weather's and {list(CAMERA_FIELDS)}")
    s = integer("seed", seed, 0, 2**64 - 1)
    if isinstance(image, (list, tuple)):
        if depth_m is not None:
            raise ValueError("depth_m is for one image; for a list, call augment on each with its depth map")
        results = [_one(np.asarray(im), s + k, None, camera, encoding, return_layers, base, fields, backend) for k, im in enumerate(image)]
        images = [o for o, _ in results]
        return (images, [lay for _, lay in results]) if return_layers else images
    arr = np.asarray(image)
    if arr.ndim == 4:
        if depth_m is not None:
            raise ValueError("depth_m is for one image; for a batch, call augment on each with its depth map")
        results = [_one(arr[k], s + k, None, camera, encoding, return_layers, base, fields, backend) for k in range(arr.shape[0])]
        batch = np.stack([o for o, _ in results]) if results else arr.copy()
        return (batch, [lay for _, lay in results]) if return_layers else batch
    out, layers = _one(arr, s, depth_m, camera, encoding, return_layers, base, fields, backend)
    return (out, layers) if return_layers else out

