"""Argument checks shared by the public modules: clear TypeErrors, broadcasting, and the
valid ranges of :data:`skyfall._core.RANGES` (declared once, in the Rust core)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall import _core

FloatOrArray = float | NDArray[np.float64]


def float_array(name: str, value: Any) -> NDArray[np.float64]:
    """Convert ``value`` to a float64 array, raising TypeError for non-real input."""
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be a real number or array of real numbers, got {type(value).__name__}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged lists and the like
        raise TypeError(f"{name} must be a real number or array of real numbers: {exc}") from exc
    if arr.dtype.kind not in "iuf":
        raise TypeError(
            f"{name} must be a real number or array of real numbers, got dtype {arr.dtype} "
            f"(from {type(value).__name__})"
        )
    return arr.astype(np.float64, copy=False)


def values(
    name: str, value: Any, dtype: Any = np.float32, *, nan: bool = False, finite: bool = False, shape: str | None = None
) -> NDArray[Any]:
    """``value`` as a C-contiguous array of ``dtype``, each refusal naming ``name``: TypeError
    for what is not real numbers, ValueError for NaN (unless ``nan``), for infinities (with
    ``finite``) and for a shape that does not match ``shape`` (``"(N, 2)"``, ``"(H, W)"``,
    ``"(N,)"``)."""
    # (an array of floats as it is: no float64 copy of a frame)
    a = value if isinstance(value, np.ndarray) and value.dtype.kind == "f" else float_array(name, value)
    if not nan and np.isnan(a).any():
        raise ValueError(f"{name} holds {int(np.count_nonzero(np.isnan(a)))} NaN values: replace them (np.nan_to_num)")
    if finite and not np.isfinite(a).all():
        raise ValueError(f"{name} holds infinities: its values must be finite")
    if shape == "(N,)":
        a = a.reshape(-1)
    elif shape == "(N, 2)":
        if a.size % 2 or (a.ndim > 1 and a.shape[-1] != 2) or a.ndim > 2:
            raise ValueError(f"{name} must have shape (N, 2), got {a.shape}")
        a = a.reshape(-1, 2)
    elif shape == "(H, W)" and (a.ndim != 2 or 0 in a.shape):
        raise ValueError(f"{name} must have shape (H, W) with H, W >= 1, got {a.shape}")
    with np.errstate(over="ignore"):
        return np.ascontiguousarray(a, dtype=dtype)


def broadcast_flat(
    arrays: Sequence[tuple[str, Any]],
) -> tuple[list[NDArray[np.float64]], tuple[int, ...]]:
    """Broadcast named inputs for a flat ``_core`` kernel.

    Returns the inputs (size-one ones as length-1 arrays, which the kernel broadcasts; the
    rest as contiguous flat arrays) and the broadcast shape. Raises ValueError naming the
    shapes when they do not broadcast.
    """
    converted = [(name, float_array(name, v)) for name, v in arrays]
    try:
        shape = np.broadcast_shapes(*(a.shape for _, a in converted))
    except ValueError:
        shapes = ", ".join(f"{n}{a.shape}" for n, a in converted)
        raise ValueError(f"shapes do not broadcast: {shapes}") from None
    flat = [
        a.reshape(1) if a.size == 1 else np.ascontiguousarray(np.broadcast_to(a, shape)).reshape(-1)
        for _, a in converted
    ]
    return flat, shape


def shaped(out: NDArray[np.float64], shape: tuple[int, ...]) -> FloatOrArray:
    """Reshape a kernel's flat result; a 0-d result becomes a Python float."""
    if shape == ():
        return float(out[0])
    return out.reshape(shape)


def choice(name: str, value: Any, options: Sequence[str]) -> str:
    """Check a string option."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str, one of {list(options)}, got {type(value).__name__}")
    if value not in options:
        raise ValueError(f"{name} = {value!r} is not one of {list(options)}")
    return value


def finite_vec3(name: str, value: Any) -> NDArray[np.float64]:
    """Check three finite real numbers (TypeError for non-numbers)."""
    v = float_array(name, value)
    if v.shape != (3,):
        raise ValueError(f"{name} must have 3 components, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} = {v.tolist()} must be finite")
    return v


def inside(name: str, value: float) -> bool:
    """Whether ``value`` lies in the declared range of ``name`` (exact for Python ints)."""
    lo, hi, lo_inclusive, hi_inclusive, _unit = _core.RANGES[name]
    above = value >= lo if lo_inclusive else value > lo
    below = value <= hi if hi_inclusive else value < hi
    return bool(above and below)


def refuse(name: str, value: float, index: int | None = None) -> None:
    """Raise the core's ValueError for ``value`` outside the range of ``name``."""
    try:
        v = float(value)
    except OverflowError:  # an int beyond float
        v = math.inf if value > 0 else -math.inf
    _core.check_range(name, v, index)  # raises with the table's message
    # Only an int that rounds into the range as a float gets here.
    lo, hi, lo_inclusive, hi_inclusive, unit = _core.RANGES[name]
    ends = f"{'[' if lo_inclusive else '('}{lo:g}, {hi:g}{']' if hi_inclusive else ')'}"
    raise ValueError(f"{name} = {value} is outside the valid range {ends} {unit}".rstrip())


def in_range(name: str, value: Any) -> float:
    """Check a real scalar against the declared range of ``name`` (TypeError for non-numbers)."""
    v = real(name, value)
    if not inside(name, v):
        refuse(name, v)
    return v


def all_in_range(name: str, values: Any) -> NDArray[np.float64]:
    """Check every element of an array against the declared range of ``name``; the first
    element outside is named by its index (for more than one element)."""
    a = float_array(name, values)
    flat = a.reshape(-1)
    lo, hi, lo_inclusive, hi_inclusive, _unit = _core.RANGES[name]
    with np.errstate(invalid="ignore"):
        ok = (flat >= lo if lo_inclusive else flat > lo) & (flat <= hi if hi_inclusive else flat < hi)
    if not np.all(ok):
        i = int(np.argmin(ok))
        refuse(name, float(flat[i]), i if flat.size > 1 else None)
    return a


def integer_in_range(name: str, value: Any) -> int:
    """Check an integer against the declared range of ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    v = int(value)
    if not inside(name, v):
        refuse(name, v)
    return v


def world_position(value: Any) -> NDArray[np.float64]:
    """Check a world position, m: three finite numbers within the declared ``position_m``."""
    p = finite_vec3("position_m", value)
    for c in p:  # the coordinate is named by its value: position_m = 2e7 is outside ...
        if not inside("position_m", float(c)):
            refuse("position_m", float(c))
    return p


def integer(name: str, value: Any, lo: int, hi: int) -> int:
    """Check an integer in [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    v = int(value)
    if not lo <= v <= hi:
        raise ValueError(f"{name} = {v} is outside the valid range [{lo}, {hi}]")
    return v


def real(name: str, value: Any) -> float:
    """Check a real scalar (range checks are the kernel's)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    return float(value)


def flag(name: str, value: Any) -> bool:
    """A switch: a bool or numpy bool only (``"no"`` or 0 would turn a switch on or off by accident)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)
