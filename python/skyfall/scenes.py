"""Scenes a frame can show: photos with depth, and procedural boxes on a ground plane.

Procedural scenes are lit by the weather's sky through the ambient-light map (see
:class:`BoxScene` and :mod:`skyfall.sky`); no external asset files are needed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import flag as _flag
from skyfall._validate import all_in_range, float_array, integer, real
from skyfall.camera import Camera
from skyfall.io import decode_srgb, decode_srgb8
from skyfall.lights import PointLight, SpotLight
from skyfall.photo import estimate_airlight, ground_plane_depth, level_camera

__all__ = ["BoxScene", "PhotoScene", "boxes", "empty", "street"]

DEFAULT_GROUND_ALBEDO = (0.12, 0.12, 0.12)
"""Asphalt-like ground albedo, linear RGB."""
DEFAULT_BOX_ALBEDO = (0.5, 0.48, 0.45)


@dataclass(frozen=True)
class BoxScene:
    """Axis-aligned boxes on an optional ground plane (y = 0), ray cast by the renderer.

    Radiance is relative: 1.0 is a white Lambertian surface lit by the whole unobstructed sky
    (E/pi for horizontal sky illuminance E). Sky pixels show the weather's sky seen through its
    rain (by default the CIE standard overcast sky: zenith 9/7, horizon 3/7 in clear air,
    flatter in rain; :mod:`skyfall.sky`). Surfaces are lit by the sky they see:
    albedo times the illuminance on their normal over E, read from the ambient-light map
    (:func:`skyfall.sky.ambient_light_map`; open ground 1, an open wall 0.396 under the clear
    overcast sky, up to 0.5 in heavy rain, less in a street canyon or under an awning, faces looking down 0), plus the
    scene's lights: albedo times I * cone * cos(theta) / r^2 / E per light that reaches the face
    (shadowed by the boxes; see :mod:`skyfall.lights`). Walls carry a 3 m grid of dark windows.

    Attributes
    ----------
    boxes : ndarray of float32, shape (N, 9)
        min xyz (m), max xyz (m), albedo rgb per box.
    ground : bool
        Whether the ground plane exists.
    ground_albedo : tuple of 3 float
        Linear RGB.
    camera : Camera
        The default viewpoint.
    lamps_m : ndarray, shape (L, 3)
        Street-lamp positions (m).
    lights : tuple of PointLight or SpotLight
        Lights that light the rain and the surfaces facing them, seen as emitters with glows.
    """

    boxes: NDArray[np.float32]
    ground: bool = True
    ground_albedo: tuple[float, float, float] = DEFAULT_GROUND_ALBEDO
    camera: Camera = field(default_factory=Camera)
    lamps_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    lights: tuple[PointLight | SpotLight, ...] = ()


BOX_KEYS = ("min", "max", "albedo")
"""The keys of a box's dict (:func:`boxes`)."""


def _camera(value: Any) -> Camera | None:
    if value is not None and not isinstance(value, Camera):
        raise TypeError(f"camera must be a skyfall.Camera or None, got {type(value).__name__}")
    return value


def _lights(value: Any) -> tuple[PointLight | SpotLight, ...]:
    """The lights as a tuple, each checked."""
    if isinstance(value, (PointLight, SpotLight)):
        raise TypeError(f"lights must be a sequence of lights, got one {type(value).__name__}: pass (light,)")
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise TypeError(f"lights must be a sequence of PointLight or SpotLight, got {type(value).__name__}")
    for i, light in enumerate(value):
        if not isinstance(light, (PointLight, SpotLight)):
            raise TypeError(f"lights[{i}] must be a PointLight or SpotLight, got {type(light).__name__}")
    return tuple(value)


def _lamps(value: Any) -> NDArray[np.float64]:
    """Lamp positions, (L, 3) finite numbers within the core's ±1e7 m."""
    if value is None:
        return np.zeros((0, 3))
    a = float_array("lamps_m", value)
    if a.size == 0:
        return np.zeros((0, 3))
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"lamps_m must have shape (L, 3), got shape {a.shape}")
    bad = np.argwhere(~(np.abs(a) <= 1e7))
    if len(bad):
        i, k = (int(v) for v in bad[0])
        raise ValueError(f"lamps_m[{i}, {k}] = {a[i, k]} is outside the valid range [-1e7, 1e7] m")
    return a


def _albedo(name: str, value: Any) -> tuple[float, float, float]:
    a = float_array(name, value).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    if a.size != 3 or not np.all((a >= 0) & (a <= 1)):
        raise ValueError(f"{name} = {value!r} must be one or three numbers in [0, 1]")
    return float(a[0]), float(a[1]), float(a[2])


def boxes(
    box_list: Sequence[Mapping[str, Any]],
    *,
    ground: bool = True,
    ground_albedo: Any = DEFAULT_GROUND_ALBEDO,
    camera: Camera | None = None,
    lamps_m: Any = None,
    lights: tuple[PointLight | SpotLight, ...] = (),
) -> BoxScene:
    """Build a scene from axis-aligned boxes.

    Parameters
    ----------
    box_list : sequence of dict
        Each with ``min`` and ``max`` corners (3 numbers, m; max > min on every axis) and an
        optional ``albedo`` (one or three numbers in [0, 1]; default a light concrete grey).
    ground : bool
        Add the ground plane y = 0.
    ground_albedo : float or 3 floats
        Linear albedo of the ground.
    camera : Camera, optional
        Default viewpoint; eye height at the origin looking along -Z when left out.
    lamps_m : array_like, shape (L, 3), optional
        Lamp positions, m.
    lights : tuple of PointLight or SpotLight
        Lights that light the rain.

    Returns
    -------
    BoxScene
    """
    arr = _box_rows(box_list, "boxes")
    cam = _camera(camera)
    return BoxScene(
        boxes=arr,
        ground=_flag("ground", ground),
        ground_albedo=_albedo("ground_albedo", ground_albedo),
        camera=cam if cam is not None else Camera(),
        lamps_m=_lamps(lamps_m),
        lights=_lights(lights),
    )


def _box_rows(box_list: Sequence[Mapping[str, Any]], name: str) -> NDArray[np.float32]:
    """(N, 9) rows (min xyz, max xyz, albedo rgb) from dicts with ``min``, ``max``, ``albedo``."""
    if isinstance(box_list, (str, bytes)) or not isinstance(box_list, Sequence):
        raise TypeError(f"{name} must be a sequence of dicts, got {type(box_list).__name__}")
    rows = []
    for i, b in enumerate(box_list):
        if not isinstance(b, Mapping):
            raise TypeError(f"{name}[{i}] must be a dict with 'min' and 'max' corners, got {type(b).__name__}")
        if "min" not in b or "max" not in b:
            raise ValueError(f"{name}[{i}] must be a dict with 'min' and 'max' corners, got {b!r}")
        unknown = sorted(str(k) for k in b if k not in BOX_KEYS)
        if unknown:
            raise ValueError(f"{name}[{i}] has unknown keys {unknown}: a box takes {list(BOX_KEYS)}")
        lo = float_array(f"{name}[{i}].min", b["min"]).reshape(-1)
        hi = float_array(f"{name}[{i}].max", b["max"]).reshape(-1)
        if lo.size != 3 or hi.size != 3 or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise ValueError(f"{name}[{i}]: min and max must be 3 finite numbers (m), got min {b['min']!r}, max {b['max']!r}")
        if np.any(hi <= lo):
            raise ValueError(f"{name}[{i}]: max {hi.tolist()} must exceed min {lo.tolist()} on every axis")
        rows.append([*lo, *hi, *_albedo(f"{name}[{i}].albedo", b.get("albedo", DEFAULT_BOX_ALBEDO))])
    return np.array(rows, dtype=np.float32).reshape(-1, 9)


def empty(*, ground_albedo: Any = DEFAULT_GROUND_ALBEDO, camera: Camera | None = None) -> BoxScene:
    """The ground plane alone under the overcast sky."""
    return boxes([], ground=True, ground_albedo=ground_albedo, camera=camera)


def street(
    *,
    length_m: float = 120.0,
    width_m: float = 14.0,
    seed: int = 0,
    lamps: bool = False,
    headlights: bool = False,
    awning: bool = True,
) -> BoxScene:
    """The bundled default scene: a street canyon seen from eye height.

    Buildings of 9-24 m line both sides of a ``width_m`` street running along -Z for
    ``length_m``, with a tall block closing the view; lamps stand every 15 m on both sides,
    2.5 m in from the building fronts, 5 m up. The camera stands at (1.5, 1.6, 0) on the street, looking down it. An awning over
    the right-hand pavement shades the rain beneath it from the sky.

    Parameters
    ----------
    length_m : float
        Street length, m, in [20, 1000].
    width_m : float
        Distance between the building fronts, m, in [4, 100].
    seed : int
        Seeds the building heights and shades (deterministic), in [0, 2^64).
    lamps : bool
        Light the lamps: warm 2000 cd point lights at the lamp heads. They light the drops,
        the street and the walls they face (with the boxes' shadows) and show as small
        emitters with a glow through the rain (see :mod:`skyfall.lights`).
    headlights : bool
        An oncoming car 12 m ahead in the other lane: two 15000 cd spots, 1.5 m apart at
        0.7 m, aimed along +Z (towards the camera) and slightly down, with 30 degree cones (the
        camera sees them at 21 and 27 degrees off their axes: one at full intensity, one
        dimmer).
    awning : bool
        A 0.25 m thick awning 3.5 m deep over the right-hand pavement, 3 m up, from 1 m to
        40 m ahead: drops beneath it see less sky (:mod:`skyfall.sky`).

    Returns
    -------
    BoxScene

    Examples
    --------
    >>> scene = street(lamps=True, headlights=True)
    >>> scene.boxes.shape, len(scene.lamps_m), len(scene.lights)  # 16 lamps lit, 2 headlights
    ((16, 9), 16, 18)
    >>> scene.camera.position_m.tolist()
    [1.5, 1.6, 0.0]
    """
    length_m = real("length_m", length_m)
    if not 20.0 <= length_m <= 1000.0:
        raise ValueError(f"length_m = {length_m} is outside the valid range [20, 1000] m")
    width_m = real("width_m", width_m)
    if not 4.0 <= width_m <= 100.0:
        raise ValueError(f"width_m = {width_m} is outside the valid range [4, 100] m")
    rng = np.random.default_rng(integer("seed", seed, 0, 2**64 - 1))
    lamps, headlights, awning = _flag("lamps", lamps), _flag("headlights", headlights), _flag("awning", awning)
    half = width_m / 2
    box_list: list[dict[str, Any]] = []
    for side in (-1, 1):
        z = -4.0
        while z > -length_m:
            depth = float(rng.uniform(10, 22))
            height = float(rng.uniform(9, 24))
            shade = float(rng.uniform(0.35, 0.65))
            tint = np.array([1.0, 0.96, 0.9]) if rng.random() < 0.5 else np.array([0.92, 0.95, 1.0])
            x0, x1 = (half, half + 12) if side > 0 else (-half - 12, -half)
            box_list.append({"min": (x0, 0, z - depth), "max": (x1, height, z), "albedo": np.clip(shade * tint, 0, 1)})
            z -= depth + float(rng.uniform(0.0, 3.0))
    box_list.append({"min": (-half - 12, 0, -length_m - 20), "max": (half + 12, 30, -length_m), "albedo": (0.55, 0.55, 0.58)})
    if awning:
        box_list.append({"min": (half - 3.5, 3.0, -min(40.0, length_m)), "max": (half, 3.25, -1.0), "albedo": (0.45, 0.12, 0.1)})
    lamp_positions = [(s * (half - 2.5), 5.0, -float(z)) for z in np.arange(8.0, length_m, 15.0) for s in (-1, 1)]
    cam = Camera((1.5, 1.6, 0.0), yaw_deg=0.0, pitch_deg=2.0, vertical_fov_deg=55.0)
    lights: list[PointLight | SpotLight] = []
    if lamps:
        lights += [PointLight(p, 2000.0, color=(1.0, 0.8, 0.55)) for p in lamp_positions]
    if headlights:
        lights += [SpotLight((x, 0.7, -12.0), (0.0, -0.05, 1.0), 15000.0, cone_deg=30.0) for x in (-4.25, -2.75)]
    return boxes(box_list, ground=True, camera=cam, lamps_m=lamp_positions, lights=tuple(lights))


def _array(name: str, value: Any, path_hint: str) -> NDArray[Any]:
    """``value`` as an array; a path or a string is a TypeError saying how to read it."""
    if isinstance(value, (str, bytes, PathLike)):
        raise TypeError(f"{name} must be an array, got the {type(value).__name__} {str(value)!r}; for {path_hint}")
    return np.asarray(value)


def _at_least_zero(name: str, a: NDArray[np.float32], unit: str, *, finite: bool) -> None:
    """Refuse NaN, negative values and, with ``finite``, infinities, naming the first one."""
    ok = np.isfinite(a) & (a >= 0) if finite else a >= 0  # NaN compares false
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


@dataclass(frozen=True)
class PhotoScene:
    """A photo with its depth map: how datasets are made from real images.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        uint8 sRGB codes, kept as given in ``srgb8`` (the input of
        :meth:`skyfall.Renderer.render_srgb8`'s fused 8-bit path) and decoded to linear with
        the sRGB transfer function when ``image`` is first read; or floats (any float dtype,
        stored as float32) whose encoding ``encoding`` states.
    depth_m : array_like, shape (H, W), optional
        Depth along the optical axis, >= 0: metres for a float map (``inf`` marks sky), or
        integer units of ``depth_scale_m`` (uint16 millimetres, as depth sensors write them,
        with ``depth_scale_m=0.001``). From a sensor or a depth estimator. Left out, the
        photo is taken to show a level ground below its horizon and sky above it
        (:func:`skyfall.photo.ground_plane_depth`, seen by ``camera`` or by a camera
        ``camera_height_m`` up whose horizon is ``horizon_row``).
    encoding : {"linear", "srgb"}, optional
        How float pixels are encoded, required for a float image (no guess: scikit-image's
        ``img_as_float`` gives sRGB-encoded floats, a skyfall frame's ``rgb`` is linear light):
        ``"linear"`` as they are, ``"srgb"`` values in [0, 1] decoded with the sRGB transfer
        function. A uint8 image is sRGB codes (``None`` or ``"srgb"``).
    depth_scale_m : float, optional
        Metres per unit of ``depth_m``: required for an integer map (there is no safe guess:
        millimetres read as metres put everything 1000x too far, into the fog), optional for a
        float one (default 1). A 0 stays 0 m (at the lens: rain in front of it is hidden); mark
        missing readings yourself, e.g. as ``inf`` in a float map.
    camera : Camera, optional
        The camera that took the photo; by default one at the origin looking along -Z with
        ``vertical_fov_deg`` (without a depth map: ``camera_height_m`` above the ground).
    vertical_fov_deg : float
        Vertical field of view, degrees, in [0.001, 179), when no camera is given (a given
        camera has its own).
    lights : tuple of PointLight or SpotLight
        Lights in the photo's world (camera coordinates when no camera is given) that light
        the rain.
    occluders : sequence of dict, optional
        Axis-aligned boxes (``min``, ``max`` corners in m, as for :func:`boxes`) in the
        photo's world that hide the sky from the drops: an awning, a bridge, a roof over the
        camera. Drops beneath them receive less sky light (:mod:`skyfall.sky`). The depth map
        is not turned into occluders: seen from one viewpoint it says nothing of what hangs
        over a drop.
    airlight : "estimate", "sky" or array_like of 3 float
        The photo's airlight, the light its rain and mist tend to with distance (and its sky
        at the horizon), linear RGB in the photo's own units, each in [0, 1e6]: everything
        the weather adds is put in these units, the haze's airlight and the drops' and lamps'
        light alike, so a dusk photo stays dusky and a photo at a quarter of the exposure
        gets a quarter of the light. ``"estimate"`` (default): the photo's horizon sky, the
        median of its lowest sky pixels, or He, Sun & Tang's atmospheric light where the depth
        map shows no sky (:func:`skyfall.photo.estimate_airlight`; give it yourself for a
        photo without sky). ``"sky"``: the photo is in the renderer's relative units
        (1 = E/pi, e.g. a skyfall frame's ``rgb``) and the weather's own airlight applies.
    camera_height_m : float, optional
        Without a depth map and a camera: the camera's height above the ground, m, in
        (0, 1e4] (default 1.6).
    horizon_row : float, optional
        Without a depth map and a camera: the image row of the level horizon, px from the top,
        in [-1e9, 1e9] (pixel centres at k + 0.5; default the middle, a level camera). It sets
        the pitch, which must stay within [-89, 89] degrees.
    """

    depth_m: NDArray[np.float32]
    camera: Camera
    lights: tuple[PointLight | SpotLight, ...]
    occluders: NDArray[np.float32]
    srgb8: NDArray[np.uint8] | None = field(repr=False)
    airlight: str | tuple[float, float, float]

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
        camera_height_m: float | None = None,
        horizon_row: float | None = None,
    ) -> None:
        img = _array("image", image, "a file: read it with skyfall.io.read_image")
        if img.dtype != np.uint8 and img.dtype.kind != "f":
            raise TypeError(f"image must be uint8 (sRGB codes) or float, got dtype {img.dtype}")
        if encoding not in (None, "linear", "srgb"):
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
        if img.ndim != 3 or img.shape[2] != 3 or img.shape[0] == 0 or img.shape[1] == 0:
            raise ValueError(f"image must have shape (H, W, 3), got {img.shape}")
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
        if depth_m is None:
            if cam is not None and (camera_height_m is not None or horizon_row is not None):
                raise ValueError("give either a camera or camera_height_m / horizon_row: the camera has its own height and pitch")
            if cam is None:
                height_m = 1.6 if camera_height_m is None else camera_height_m
                cam = level_camera(w, h, camera_height_m=height_m, horizon_row=horizon_row, vertical_fov_deg=fov)
            if depth_scale_m is not None:
                raise ValueError("depth_scale_m needs a depth_m to scale")
            d = ground_plane_depth(cam.with_resolution(w, h))
        else:
            if camera_height_m is not None or horizon_row is not None:
                raise ValueError("camera_height_m and horizon_row shape the ground-plane depth used without a depth map; this photo has one")
            d = self._depth(depth_m, depth_scale_m, img.shape[:2])
        if cam is None:
            cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=fov)
        object.__setattr__(self, "srgb8", srgb8)
        object.__setattr__(self, "depth_m", d)
        object.__setattr__(self, "camera", cam.with_resolution(w, h))
        object.__setattr__(self, "lights", _lights(lights))
        object.__setattr__(self, "occluders", _box_rows(occluders, "occluders"))
        object.__setattr__(self, "airlight", _airlight(airlight))

    @staticmethod
    def _depth(depth_m: Any, depth_scale_m: float | None, shape: tuple[int, ...]) -> NDArray[np.float32]:
        """A given depth map in metres (float32), checked."""
        d = _array("depth_m", depth_m, "a file: read it with skyfall.io.read_channels")
        if d.dtype.kind not in "fiu":
            raise TypeError(f"depth_m must be numeric, got dtype {d.dtype}")
        if depth_scale_m is None and d.dtype.kind in "iu":
            raise TypeError(
                f"depth_m is {d.dtype}: give depth_scale_m, its metres per unit (0.001 for millimetres, "
                "as depth sensors write them); integer depth has no unit of its own"
            )
        scale = 1.0 if depth_scale_m is None else real("depth_scale_m", depth_scale_m)
        if not (math.isfinite(scale) and scale > 0.0):
            raise ValueError(f"depth_scale_m = {scale} must be a positive finite number of metres per unit")
        d = np.ascontiguousarray(d, dtype=np.float32) if scale == 1.0 else np.ascontiguousarray(d.astype(np.float64) * scale, dtype=np.float32)
        if d.shape != shape:
            raise ValueError(f"depth_m has shape {d.shape}, the image is {shape}")
        _at_least_zero("depth_m", d, " m (inf for sky)", finite=False)
        return d

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
