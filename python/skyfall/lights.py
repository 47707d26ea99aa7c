"""Point and spot lights: street lamps and headlights.

A light of intensity I (cd) at distance r gives the illuminance I * cone / r^2 (lux, per colour
channel) on a surface facing it. In a box scene a light

- lights the rain drops: a drop's light I_R grows by that illuminance over the sky's
  (see :class:`skyfall.Weather`), so at dusk (low ``sky_illuminance_lux``) drops near lamps
  shine;
- lights the surfaces that face it: a Lambertian face of albedo a gains a * I * cone * cos(theta)
  / r^2 / E in the frame's relative units (1.0 = white under the open sky of horizontal
  illuminance E), shadowed by the scene's boxes;
- shows as an emitter (a disc 0.15 m across) with a glow: the light scattered by the rain and
  mist on its way to the camera, spread wider as the optical depth to it grows (an atmospheric
  point-spread function after Narasimhan & Nayar, "Shedding light on the weather", 2003),
  unless a box hides it.

A :class:`skyfall.PhotoScene`'s lights are lights in the photo's world: they light its drops
only (a photo has no normals to light, and no glows are drawn over photos). The core reads a
light's fields directly (one frame request).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from skyfall._validate import all_in_range, finite_vec3, in_range, real, world_position

__all__ = ["PointLight", "SpotLight"]


def _vec3(name: str, value: Any) -> tuple[float, float, float]:
    x, y, z = finite_vec3(name, value)
    return float(x), float(y), float(z)


def _position(value: Any) -> tuple[float, float, float]:
    x, y, z = world_position(value)
    return float(x), float(y), float(z)


def _color(value: Any) -> tuple[float, float, float]:
    r, g, b = all_in_range("color", _vec3("color", value))
    return float(r), float(g), float(b)


def _unit(name: str, value: Any) -> tuple[float, float, float]:
    d = np.asarray(_vec3(name, value))
    # scaled by its largest component first, so that huge or tiny vectors normalise too
    m = float(np.max(np.abs(d)))
    if m == 0.0:
        raise ValueError(f"{name} must not be zero")
    d = d / m
    d = d / np.linalg.norm(d)
    return float(d[0]), float(d[1]), float(d[2])


@dataclass(frozen=True)
class PointLight:
    """A light shining equally in all directions.

    Parameters
    ----------
    position_m : 3 floats
        Position, m, each coordinate in [-1e7, 1e7].
    intensity_cd : float
        Luminous intensity, cd, in [0, 1e9] (a street lamp: about 1000-3000 cd).
    color : 3 floats
        Linear RGB multiplier of the intensity, each in [0, 1000].
    """

    position_m: tuple[float, float, float]
    intensity_cd: float
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "position_m", _position(self.position_m))
        object.__setattr__(self, "color", _color(self.color))
        in_range("intensity_cd", self.intensity_cd)


@dataclass(frozen=True)
class SpotLight:
    """A light shining in a cone (a headlight).

    Parameters
    ----------
    position_m : 3 floats
        Position, m, each coordinate in [-1e7, 1e7].
    direction : 3 floats
        Axis of the cone (normalised here).
    intensity_cd : float
        Luminous intensity on the axis, cd, in [0, 1e9] (a low-beam headlight: about
        10000-20000 cd).
    cone_deg : float
        Outer half-angle, degrees in (0, 90]: no light beyond it.
    inner_cone_deg : float, optional
        Half-angle of full intensity (default 0.75 * cone_deg); smooth falloff between.
    color : 3 floats
        Linear RGB multiplier of the intensity, each in [0, 1000].
    """

    position_m: tuple[float, float, float]
    direction: tuple[float, float, float]
    intensity_cd: float
    cone_deg: float = 30.0
    inner_cone_deg: float | None = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "position_m", _position(self.position_m))
        object.__setattr__(self, "direction", _unit("direction", self.direction))
        object.__setattr__(self, "color", _color(self.color))
        in_range("intensity_cd", self.intensity_cd)
        in_range("cone_deg", self.cone_deg)
        inner = 0.75 * float(self.cone_deg) if self.inner_cone_deg is None else real("inner_cone_deg", self.inner_cone_deg)
        if not 0.0 <= inner <= float(self.cone_deg):
            raise ValueError(f"inner_cone_deg = {inner} must be in [0, cone_deg = {self.cone_deg}]")
        object.__setattr__(self, "inner_cone_deg", inner)


Light = PointLight | SpotLight
