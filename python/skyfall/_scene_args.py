"""Argument checks shared by the box scenes and the photo scene: cameras, lights, boxes."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import float_array
from skyfall.camera import Camera
from skyfall.lights import PointLight, SpotLight

DEFAULT_BOX_ALBEDO = (0.5, 0.48, 0.45)
"""A light concrete grey, a box's albedo when none is given."""

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


def _albedo(name: str, value: Any) -> tuple[float, float, float]:
    a = float_array(name, value).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    if a.size != 3 or not np.all((a >= 0) & (a <= 1)):
        raise ValueError(f"{name} = {value!r} must be one or three numbers in [0, 1]")
    return float(a[0]), float(a[1]), float(a[2])


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
