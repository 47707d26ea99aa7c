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
from skyfall._scene_args import BOX_KEYS, DEFAULT_BOX_ALBEDO, _albedo, _box_rows, _camera, _lights
from skyfall.photo_scene import PhotoScene

__all__ = ["BoxScene", "PhotoScene", "boxes", "empty", "street"]

DEFAULT_GROUND_ALBEDO = (0.12, 0.12, 0.12)
"""Asphalt-like ground albedo, linear RGB."""


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
