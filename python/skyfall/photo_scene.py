"""A photo as a scene: its pixels, its depth (given, read from a file, or assumed) and where
it shows sky. Every output that draws a photo (haze, rain and its shelter, snow, clouds, the
windshield, the dataset's layers; the CPU paths and the GPU alike) reads this one object."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._scene_args import _box_rows, _camera, _lights
from skyfall._validate import all_in_range, float_array, in_range, real
from skyfall.camera import Camera
from skyfall.io import decode_srgb, decode_srgb8
from skyfall.lights import PointLight, SpotLight
from skyfall.photo import assumed_depth, estimate_airlight, fill_depth_holes, level_camera, sky_level_camera
from skyfall.sky_mask import estimate_sky_mask

__all__ = ["DEFAULT_DISTANCE_M", "PhotoScene"]

DEFAULT_DISTANCE_M = 10.0
"""The distance, m, a photo without a depth map is taken to show wherever it shows no sky:
the whole default rain region (``Weather.rain_near_m``) lies in front of it, and 10 m of the
heaviest rain's haze takes a few percent of its contrast, so the photo keeps its content."""


def _array(name: str, value: Any, path_hint: str) -> NDArray[Any]:
    """``value`` as an array; a path or a string is a TypeError saying how to read it."""
    if isinstance(value, (str, bytes, PathLike)):
        raise TypeError(f"{name} must be an array, got the {type(value).__name__} {str(value)!r}; for {path_hint}")
    return np.asarray(value)


def _at_least_zero(name: str, a: NDArray[np.float32], unit: str, *, finite: bool, nan: bool = False) -> None:
    """Refuse negative values, NaN (unless ``nan``) and, with ``finite``, infinities, naming the first one."""
    ok = np.isfinite(a) & (a >= 0) if finite else a >= 0  # NaN compares false
    if nan:
        ok |= np.isnan(a)
    if not ok.all():
        at = tuple(int(v) for v in np.argwhere(~ok)[0])
        valid = "[0, inf)" if finite else "[0, inf]"
        raise ValueError(f"{name}[{', '.join(map(str, at))}] = {a[at]} is outside the valid range {valid}{unit}")


def _airlight(value: Any) -> str | tuple[float, float, float]:
    """``"estimate"``, ``"sky"``, or three linear values >= 0 (one is taken as grey)."""
    if isinstance(value, str):
        if value not in ("estimate", "sky"):
            raise ValueError(f"airlight = {value!r} must be \"estimate\", \"sky\" or 3 linear RGB values")
        return value
    a = float_array("airlight", value).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    if a.size != 3:
        raise ValueError(f"airlight must be \"estimate\", \"sky\" or 3 linear RGB values, got {a.size} values")
    a = all_in_range("airlight", a)
    return (float(a[0]), float(a[1]), float(a[2]))


def _user_mask(value: Any, shape: tuple[int, int]) -> NDArray[np.bool_] | None:
    """A given sky mask, checked; None for ``"estimate"``."""
    if isinstance(value, str):
        if value != "estimate":
            raise ValueError(f"sky_mask = {value!r} must be \"estimate\", None (no sky) or a boolean (H, W) array")
        return None
    if value is None:
        return np.zeros(shape, dtype=bool)
    m = _array("sky_mask", value, "a mask file: read it with skyfall.io.read_image")
    if m.dtype != np.bool_:
        raise TypeError(f"sky_mask must be a boolean array (True = sky), got dtype {m.dtype}")
    if m.shape != shape:
        raise ValueError(f"sky_mask has shape {m.shape}, the image is {shape}")
    return np.ascontiguousarray(m)


def _given_depth(depth_m: Any, depth_scale_m: float | None, shape: tuple[int, int]) -> NDArray[np.float32]:
    """A given depth map in metres (float32, NaN = no data), checked."""
    d = _array("depth_m", depth_m, "a file: read it with skyfall.io.read_depth")
    if d.dtype.kind not in "fiu":
        raise TypeError(f"depth_m must be numeric, got dtype {d.dtype}")
    if d.dtype.kind in "iu":
        if depth_scale_m is None:
            raise TypeError(
                f"depth_m is {d.dtype}: give depth_scale_m, its metres per unit (0.001 for millimetres, "
                "as depth sensors write them); integer depth has no unit of its own"
            )
        scale = real("depth_scale_m", depth_scale_m)
        if not (math.isfinite(scale) and scale > 0.0):
            raise ValueError(f"depth_scale_m = {scale} must be a positive finite number of metres per unit")
        if d.shape != shape:
            raise ValueError(f"depth_m has shape {d.shape}, the image is {shape}")
        out = (d.astype(np.float64) * scale).astype(np.float32)
        out[d == 0] = np.nan  # 0 is a sensor's "no reading"
        _at_least_zero("depth_m", out, " m (inf for sky)", finite=False, nan=True)
        return np.ascontiguousarray(out)
    if depth_scale_m is not None:
        raise ValueError(f"depth_scale_m applies to integer depth only: depth_m is {d.dtype}, metres already")
    if d.shape != shape:
        raise ValueError(f"depth_m has shape {d.shape}, the image is {shape}")
    out = np.ascontiguousarray(d, dtype=np.float32)
    _at_least_zero("depth_m", out, " m (inf for sky, NaN for no data)", finite=False, nan=True)
    return out


@dataclass(frozen=True)
class PhotoScene:
    """A photo, with or without a depth map: how weather is put on real images.

    **The scene model.** Each pixel has a depth along the optical axis (m) or shows sky
    (``inf``), and :attr:`sky_mask` is exactly where the depth is ``inf``:

    - with ``depth_m``: that map (from a sensor, a file read by :func:`skyfall.io.read_depth`,
      or :func:`skyfall.depth.estimate`); its ``NaN`` holes are filled
      (:func:`skyfall.photo.fill_depth_holes`: sky where the sky mask says so, else the
      nearest pixel with data);
    - without one: everything that is not sky at ``distance_m`` (default
      :data:`DEFAULT_DISTANCE_M`, 10 m), so the photo never loses its content to the haze
      and the rain in front of it still shows; the camera (unless given) is level, pitched up
      just enough that no sky pixel looks below the horizon
      (:func:`skyfall.photo.sky_level_camera`), so the sky is hazed along rays that rise;
    - the level ground plane below the horizon (:func:`skyfall.photo.ground_plane_depth`)
      only when asked for with ``camera_height_m`` and/or ``horizon_row``: the ground up to
      ``distance_m``, everything else not sky at ``distance_m``.

    Sky comes from ``sky_mask``: estimated from the pixels by default
    (:func:`skyfall.photo.estimate_sky_mask`, a cautious classical estimator), given by the
    user, or none (``sky_mask=None``); a depth map's own ``inf`` pixels are sky too. Sky
    pixels are hazed along the whole path to the cloud base, and clouds are drawn only there,
    behind everything else.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        uint8 sRGB codes, kept as given in ``srgb8`` (the input of
        :meth:`skyfall.Renderer.render_srgb8`'s fused 8-bit path) and decoded to linear with
        the sRGB transfer function when ``image`` is first read; or floats (any float dtype,
        stored as float32) whose encoding ``encoding`` states.
    depth_m : array_like, shape (H, W), optional
        Depth along the optical axis, >= 0: metres for a float map (``inf`` marks sky,
        ``NaN`` no data), or integer units of ``depth_scale_m`` (uint16 millimetres, as depth
        sensors write them, with ``depth_scale_m=0.001``; 0 marks no data).
    encoding : {"linear", "srgb"}, optional
        How float pixels are encoded, required for a float image (no guess: scikit-image's
        ``img_as_float`` gives sRGB-encoded floats, a skyfall frame's ``rgb`` is linear light):
        ``"linear"`` as they are, ``"srgb"`` values in [0, 1] decoded with the sRGB transfer
        function. A uint8 image is sRGB codes (``None`` or ``"srgb"``).
    depth_scale_m : float, optional
        Metres per unit of an integer ``depth_m``: required there (there is no safe guess:
        millimetres read as metres put everything 1000x too far, into the fog), refused with
        float depth, which is metres already.
    camera : Camera, optional
        The camera that took the photo; by default one at the origin looking along -Z with
        ``vertical_fov_deg`` (with the ground plane: ``camera_height_m`` above it, pitched to
        put the horizon on ``horizon_row``).
    vertical_fov_deg : float
        Vertical field of view, degrees, in [0.001, 179), when no camera is given (a given
        camera has its own; :meth:`read` takes it from the photo's EXIF focal length).
    lights : tuple of PointLight or SpotLight
        Lights in the photo's world (camera coordinates when no camera is given) that light
        the rain.
    occluders : sequence of dict, optional
        Axis-aligned boxes (``min``, ``max`` corners in m, as for :func:`skyfall.scenes.boxes`)
        in the photo's world that hide the sky from the drops: an awning, a bridge, a roof over
        the camera. Drops beneath them receive less sky light (:mod:`skyfall.sky`). The depth
        map is not turned into occluders: seen from one viewpoint it says nothing of what
        hangs over a drop.
    airlight : "estimate", "sky" or array_like of 3 float
        The photo's airlight, the light its rain and mist tend to with distance (and its sky
        at the horizon), linear RGB in the photo's own units, each in [0, 1e6]: everything
        the weather adds is put in these units, the haze's airlight and the drops' and lamps'
        light alike, so a dusk photo stays dusky and a photo at a quarter of the exposure
        gets a quarter of the light. ``"estimate"`` (default): the photo's horizon sky where
        it shows sky, else a neutral grey (:func:`skyfall.photo.estimate_airlight`).
        ``"sky"``: the photo is in the renderer's relative units (1 = E/pi, e.g. a skyfall
        frame's ``rgb``) and the weather's own airlight applies.
    sky_mask : "estimate", None or array_like of bool, shape (H, W)
        Where the photo shows sky: ``"estimate"`` (default) from its pixels (with a depth map:
        its ``inf`` pixels, and the estimate only inside its ``NaN`` holes), ``None`` for a
        photo without sky, or your own mask (True = sky), which overrides a depth map's
        ``inf``.
    distance_m : float, optional
        Without a depth map: the distance of everything that is not sky (and the farthest
        the ground plane reaches), m, in (0, 1e5] (default 10).
    camera_height_m : float, optional
        Asks for the ground plane: the camera's height above it, m, in (0, 1e4] (default
        1.6 when only ``horizon_row`` is given). Not with ``depth_m`` or ``camera``.
    horizon_row : float, optional
        Asks for the ground plane: the image row of the level horizon, px from the top, in
        [-1e9, 1e9] (pixel centres at k + 0.5; default the middle, a level camera). It sets
        the pitch, which must stay within [-89, 89] degrees.

    Examples
    --------
    >>> import numpy as np
    >>> photo = PhotoScene(np.full((30, 40, 3), 128, np.uint8))  # no depth, no sky
    >>> float(photo.depth_m.min()), float(photo.depth_m.max()), bool(photo.sky_mask.any())
    (10.0, 10.0, False)
    """

    depth_m: NDArray[np.float32]
    camera: Camera
    lights: tuple[PointLight | SpotLight, ...]
    occluders: NDArray[np.float32]
    srgb8: NDArray[np.uint8] | None = field(repr=False)
    airlight: str | tuple[float, float, float]
    depth_source: str

    def __init__(
        self,
        image: Any,
        depth_m: Any = None,
        *,
        camera: Camera | None = None,
        vertical_fov_deg: float = 60.0,
        lights: tuple[PointLight | SpotLight, ...] = (),
        occluders: Sequence[Mapping[str, Any]] = (),
        depth_scale_m: float | None = None,
        encoding: str | None = None,
        airlight: Any = "estimate",
        sky_mask: Any = "estimate",
        distance_m: float | None = None,
        camera_height_m: float | None = None,
        horizon_row: float | None = None,
    ) -> None:
        img = _array("image", image, "a file: read it with skyfall.io.read_image or PhotoScene.read")
        if img.dtype != np.uint8 and img.dtype.kind != "f":
            raise TypeError(f"image must be uint8 (sRGB codes) or float, got dtype {img.dtype}")
        if encoding is not None and not (isinstance(encoding, str) and encoding in ("linear", "srgb")):
            raise ValueError(f"encoding = {encoding!r} must be \"linear\" or \"srgb\"")
        if img.dtype == np.uint8 and encoding == "linear":
            raise ValueError("encoding = 'linear' does not fit a uint8 image: 8-bit images are sRGB codes")
        if img.dtype != np.uint8 and encoding is None:
            # No guess: scikit-image's img_as_float gives sRGB-encoded floats, a skyfall frame
            # linear ones, and reading one as the other shifts every colour.
            raise ValueError(
                f"image is {img.dtype}: say how it is encoded, encoding='linear' (linear light, e.g. a "
                "skyfall frame's rgb) or encoding='srgb' (sRGB-encoded values in [0, 1], e.g. "
                "skimage.img_as_float of a photo)"
            )
        if img.ndim == 3 and img.shape[2] == 4:
            raise ValueError(
                f"image has shape {img.shape}, RGBA: the weather is put on the colour, so pass image[..., :3] "
                "and keep the alpha yourself (a PhotoScene holds no alpha)"
            )
        if img.ndim != 3 or img.shape[2] != 3 or img.shape[0] == 0 or img.shape[1] == 0:
            raise ValueError(f"image must have shape (H, W, 3), got {img.shape}")
        lo, hi = int(_core.RANGES["width"][0]), int(_core.RANGES["width"][1])
        if not (lo <= img.shape[0] <= hi and lo <= img.shape[1] <= hi):  # before any copy of it
            raise ValueError(f"image is {img.shape[1]}x{img.shape[0]} px: a photo's width and height lie within [{lo}, {hi}] px")
        srgb8: NDArray[np.uint8] | None = None
        if img.dtype == np.uint8:
            srgb8 = np.ascontiguousarray(img)  # decoded when `image` is first read
        else:
            lin = np.ascontiguousarray(img, dtype=np.float32)
            if encoding == "srgb":
                if not np.all((lin >= 0.0) & (lin <= 1.0)):
                    raise ValueError("image: sRGB-encoded values must lie in [0, 1] (NaN included in the check)")
                lin = decode_srgb(lin)
            _at_least_zero("image", lin, " (linear RGB)", finite=True)
            self.__dict__["image"] = lin  # the cached value of the `image` property
        h, w = img.shape[:2]
        fov = real("vertical_fov_deg", vertical_fov_deg)
        cam = _camera(camera)
        mask = _user_mask(sky_mask, (h, w))
        dist = DEFAULT_DISTANCE_M if distance_m is None else in_range("distance_m", distance_m)
        ground = camera_height_m is not None or horizon_row is not None
        if depth_m is None:
            if cam is not None and ground:
                raise ValueError("give either a camera or camera_height_m / horizon_row: the camera has its own height and pitch")
            if depth_scale_m is not None:
                raise ValueError("depth_scale_m needs a depth_m to scale")
            sky = mask if mask is not None else estimate_sky_mask(img, encoding=encoding)
            if ground:
                cam = level_camera(w, h, camera_height_m=1.6 if camera_height_m is None else camera_height_m, horizon_row=horizon_row, vertical_fov_deg=fov)
            if cam is None:
                cam = sky_level_camera(w, h, sky, vertical_fov_deg=fov)
            cam = cam.with_resolution(w, h)
            d = assumed_depth(cam, sky_mask=sky, distance_m=dist, ground_plane=ground)
            source = "ground_plane" if ground else "distance"
        else:
            if ground:
                raise ValueError("camera_height_m and horizon_row ask for the ground plane, used without a depth map; this photo has one")
            if distance_m is not None:
                raise ValueError("distance_m is the depth assumed without a depth map; this photo has one")
            d = _given_depth(depth_m, depth_scale_m, (h, w))
            if mask is not None:  # the user's mask over the map's own sky
                d = np.where(mask, np.float32(np.inf), np.where(np.isinf(d), np.float32(np.nan), d)).astype(np.float32)
            holes = np.isnan(d)
            if holes.any():
                hole_sky = mask if mask is not None else estimate_sky_mask(img, encoding=encoding) & holes
                d = fill_depth_holes(d, hole_sky)
            if cam is None:
                cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=fov)
            source = "depth_m"
        object.__setattr__(self, "srgb8", srgb8)
        object.__setattr__(self, "depth_m", np.ascontiguousarray(d, dtype=np.float32))
        object.__setattr__(self, "camera", cam.with_resolution(w, h))
        object.__setattr__(self, "lights", _lights(lights))
        object.__setattr__(self, "occluders", _box_rows(occluders, "occluders"))
        object.__setattr__(self, "airlight", _airlight(airlight))
        object.__setattr__(self, "depth_source", source)

    @classmethod
    def read(
        cls,
        path: str | Path,
        depth: str | Path | None = None,
        *,
        depth_format: str | None = None,
        depth_scale_m: float | None = None,
        camera_json: str | Path | None = None,
        calib: str | Path | None = None,
        vertical_fov_deg: float | None = None,
        **options: Any,
    ) -> PhotoScene:
        """A photo and its depth map from files (OpenImageIO; :func:`skyfall.io.read_depth`).

        The vertical field of view is ``vertical_fov_deg`` when given, else the photo's EXIF
        35 mm-equivalent focal length's (:func:`skyfall.photo.exif_vertical_fov_deg`), else
        60 degrees. An 8-bit photo keeps its codes (the fused 8-bit path), a 16-bit one is
        read as sRGB, a float one as linear light; an alpha channel is dropped (the weather
        is put on the colour; keep the alpha yourself).

        Parameters
        ----------
        path : str or Path
            The photo.
        depth : str or Path, optional
            Its depth file; None: the scene model without depth.
        depth_format, depth_scale_m, camera_json, calib
            As for :func:`skyfall.io.read_depth`.
        vertical_fov_deg : float, optional
            Overrides the EXIF field of view.
        **options
            The other :class:`PhotoScene` parameters (``sky_mask``, ``distance_m``, ...).

        Returns
        -------
        PhotoScene
        """
        from skyfall.dataset.io import read_photo
        from skyfall.depth_io import read_depth
        from skyfall.photo import exif_vertical_fov_deg

        image, encoding, meta = read_photo(Path(path), with_metadata=True)
        fov = vertical_fov_deg if vertical_fov_deg is not None else exif_vertical_fov_deg(meta, image.shape[1], image.shape[0])
        d = None
        if depth is not None:
            d = read_depth(depth, depth_format, depth_scale_m=depth_scale_m, camera_json=camera_json, calib=calib)
        elif depth_format is not None or depth_scale_m is not None or camera_json is not None or calib is not None:
            raise ValueError("depth_format, depth_scale_m, camera_json and calib describe a depth file: give depth=")
        if "camera" not in options:
            options["vertical_fov_deg"] = 60.0 if fov is None else fov
        return cls(image, d, encoding=encoding, **options)

    @property
    def sky_mask(self) -> NDArray[np.bool_]:
        """Where the photo shows sky, (H, W) bool: exactly where :attr:`depth_m` is ``inf``."""
        return np.isinf(self.depth_m)

    @cached_property
    def airlight_linear(self) -> tuple[float, float, float] | None:
        """The airlight in use, linear RGB in the photo's units (estimated on first use for
        ``airlight="estimate"``), or None for ``airlight="sky"``."""
        if self.airlight == "sky":
            return None
        if self.airlight == "estimate":
            src = self.srgb8 if self.srgb8 is not None else self.image
            a = estimate_airlight(src, depth_m=self.depth_m, camera=self.camera)
            return (float(a[0]), float(a[1]), float(a[2]))
        assert not isinstance(self.airlight, str)
        return self.airlight

    @cached_property
    def image(self) -> NDArray[np.float32]:
        """The photo in linear RGB, (H, W, 3) float32 (an 8-bit photo is decoded on first use)."""
        return decode_srgb8(self.srgb8)

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) in px."""
        return (int(self.depth_m.shape[0]), int(self.depth_m.shape[1]))
