"""Depth maps from the files users have: KITTI, Cityscapes, Middlebury, EXR, NPY and scaled
16-bit images, as float32 metres along the optical axis (``inf`` = sky, ``NaN`` = no data).

:func:`read_depth` is also :func:`skyfall.io.read_depth`. Each format's rule:

- ``"kitti"`` (KITTI depth completion / prediction, Uhrig et al. 2017): uint16 PNG, depth in
  metres x 256; 0 marks no data.
- ``"cityscapes"`` (Cordts et al. 2016): uint16 PNG disparity, d = (p - 1) / 256 px for
  p > 0 (0 marks no data); depth = baseline * fx / d from the image's ``camera`` JSON file
  (``extrinsic.baseline`` in m, ``intrinsic.fx`` in px); d = 0 is infinitely far (``inf``).
- ``"middlebury"`` (Scharstein et al. 2014): a PFM disparity map (``inf`` marks no data)
  with the scene's ``calib.txt`` (``cam0``'s focal length f in px, ``doffs`` in px,
  ``baseline`` in mm): depth = baseline * f / (d + doffs), converted to metres.
- ``"exr"``: a float channel named ``depth_m``, ``Z``, ``z`` or ``depth``, or the only one,
  in metres.
- ``"npy"``: a float array in metres as stored; an integer array in units of
  ``depth_scale_m`` (0 marks no data).
- ``"scaled"``: a 16-bit PNG or TIFF of integer units of ``depth_scale_m`` (0.001 for the
  millimetres depth sensors write; 0 marks no data).

A scale applies to integer depth only: float depth is metres already, and ``depth_scale_m``
with it is refused by name.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["DEPTH_FORMATS", "read_depth", "read_pfm", "format_for"]

DEPTH_FORMATS = ("kitti", "cityscapes", "middlebury", "exr", "npy", "scaled")
"""The formats :func:`read_depth` reads."""
_BY_SUFFIX = {".npy": "npy", ".exr": "exr", ".pfm": "middlebury", ".png": "scaled", ".tif": "scaled", ".tiff": "scaled"}


def format_for(path: str | Path) -> str:
    """The format a file's suffix implies (``.png``/``.tif``: ``"scaled"``; ``.pfm``:
    ``"middlebury"``), for ``format=None``."""
    suffix = Path(path).suffix.lower()
    if suffix not in _BY_SUFFIX:
        raise ValueError(f"{Path(path).name}: cannot tell a depth format from the suffix {suffix!r}; give format=, one of {list(DEPTH_FORMATS)}")
    return _BY_SUFFIX[suffix]


def read_pfm(path: str | Path) -> NDArray[np.float32]:
    """A Portable Float Map's single channel (``Pf``) as float32 (H, W), top row first.

    Raises
    ------
    ValueError
        When the file is not a one-channel PFM.
    """
    p = Path(path)
    data = p.read_bytes()
    m = re.match(rb"(P[fF])\s+(\d+)\s+(\d+)\s+(\S+)\s", data)
    if m is None:
        raise ValueError(f"{p.name} is not a PFM file (expected a 'Pf' header: width, height, scale)")
    if m.group(1) != b"Pf":
        raise ValueError(f"{p.name} is a 3-channel PFM ('PF'); a disparity map has one channel ('Pf')")
    w, h, scale = int(m.group(2)), int(m.group(3)), float(m.group(4))
    dtype = "<f4" if scale < 0 else ">f4"
    start = m.end()
    if len(data) - start < w * h * 4 or w == 0 or h == 0:
        raise ValueError(f"{p.name}: a {w}x{h} PFM needs {w * h * 4} bytes of pixels, it has {len(data) - start}")
    arr = np.frombuffer(data, dtype=dtype, count=w * h, offset=start).reshape(h, w)
    return np.ascontiguousarray(arr[::-1], dtype=np.float32)  # PFM rows run bottom to top


def _middlebury_calib(path: Path) -> tuple[float, float, float]:
    """(f px, doffs px, baseline mm) from a Middlebury ``calib.txt``."""
    if not path.is_file():
        raise FileNotFoundError(f"calib = {str(path)!r} not found: a Middlebury disparity needs its calib.txt (cam0, doffs, baseline)")
    text = path.read_text()
    values: dict[str, str] = {}
    for line in text.splitlines():
        if "=" in line:
            k, v = line.split("=", 1)
            values[k.strip()] = v.strip()
    try:
        f = float(values["cam0"].strip("[]").replace(";", " ").split()[0])
        return f, float(values["doffs"]), float(values["baseline"])
    except (KeyError, ValueError, IndexError) as exc:
        raise ValueError(f"{path.name} lacks cam0 = [f 0 cx; ...], doffs or baseline: {exc}") from None


def _cityscapes_camera(path: Path) -> tuple[float, float]:
    """(baseline m, fx px) from a Cityscapes camera JSON file."""
    if not path.is_file():
        raise FileNotFoundError(f"camera_json = {str(path)!r} not found: a Cityscapes disparity needs its camera file")
    try:
        cam = json.loads(path.read_text())
        return float(cam["extrinsic"]["baseline"]), float(cam["intrinsic"]["fx"])
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path.name} is not a Cityscapes camera file (extrinsic.baseline, intrinsic.fx): {exc}") from None


def _stored(path: Path) -> tuple[NDArray[Any], list[str]]:
    from skyfall import io

    arr, meta = io.read_stored(path)
    return arr, list(meta["channel_names"])


def _uint16(path: Path, fmt: str) -> NDArray[np.uint16]:
    arr, _ = _stored(path)
    if arr.dtype != np.uint16:
        raise ValueError(f"{path.name} holds {arr.dtype} pixels: {fmt} depth is a 16-bit PNG")
    return np.ascontiguousarray(arr[..., 0])


def _scale(depth_scale_m: Any) -> float:
    from skyfall._validate import real

    s = real("depth_scale_m", depth_scale_m)
    if not (math.isfinite(s) and s > 0.0):
        raise ValueError(f"depth_scale_m = {s} must be a positive finite number of metres per unit")
    return s


def _scaled(codes: NDArray[Any], depth_scale_m: Any, name: str) -> NDArray[np.float32]:
    if depth_scale_m is None:
        raise ValueError(f"{name} holds integer depth ({codes.dtype}): give depth_scale_m, its metres per unit (0.001 for millimetres)")
    d = codes.astype(np.float64) * _scale(depth_scale_m)
    d[codes == 0] = np.nan
    return d.astype(np.float32)


def read_depth(
    path: str | Path,
    format: str | None = None,  # noqa: A002 - the user's word for it
    *,
    depth_scale_m: float | None = None,
    camera_json: str | Path | None = None,
    calib: str | Path | None = None,
) -> NDArray[np.float32]:
    """Read a depth map as float32 metres along the optical axis: ``inf`` = sky (or
    infinitely far), ``NaN`` = no data (filled by :class:`skyfall.PhotoScene`).

    Parameters
    ----------
    path : str or Path
        The depth file.
    format : {"kitti", "cityscapes", "middlebury", "exr", "npy", "scaled"}, optional
        Its format (module docstring: each one's rule). None: from the suffix (``.npy``,
        ``.exr``, ``.pfm`` as Middlebury, ``.png``/``.tif`` as ``"scaled"``).
    depth_scale_m : float, optional
        Metres per unit of integer depth (``"scaled"``, integer ``"npy"``); refused with
        float depth and with the formats that fix their own units.
    camera_json : str or Path, optional
        ``"cityscapes"``: the image's camera file (baseline and fx). Required.
    calib : str or Path, optional
        ``"middlebury"``: the scene's ``calib.txt`` (default: beside the PFM).

    Returns
    -------
    ndarray of float32, shape (H, W)

    Raises
    ------
    ValueError
        For an unknown format, a file that does not fit its format, a missing or refused
        ``depth_scale_m``, or negative depth.
    FileNotFoundError, OSError
        When a file cannot be found or read.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "d.npy"
    >>> np.save(p, np.array([[1500, 0]], np.uint16))
    >>> read_depth(p, depth_scale_m=0.001).tolist()
    [[1.5, nan]]
    """
    p = Path(path)
    fmt = format_for(p) if format is None else format
    if fmt not in DEPTH_FORMATS:
        raise ValueError(f"format = {fmt!r} is not one of {list(DEPTH_FORMATS)}")
    if not p.is_file():
        raise FileNotFoundError(f"depth file {str(p)!r} not found")
    if fmt in ("kitti", "cityscapes", "middlebury", "exr") and depth_scale_m is not None:
        raise ValueError(f"depth_scale_m applies to integer depth only: {fmt} depth has its own units")
    if fmt != "cityscapes" and camera_json is not None:
        raise ValueError("camera_json is for format='cityscapes'")
    if fmt != "middlebury" and calib is not None:
        raise ValueError("calib is for format='middlebury'")
    if fmt == "kitti":
        codes = _uint16(p, "KITTI")
        d = codes.astype(np.float32) / np.float32(256.0)
        d[codes == 0] = np.nan
    elif fmt == "cityscapes":
        if camera_json is None:
            raise ValueError("format='cityscapes' needs camera_json=, the image's camera file (baseline and fx)")
        baseline_m, fx = _cityscapes_camera(Path(camera_json))
        codes = _uint16(p, "Cityscapes disparity")
        disparity = (codes.astype(np.float64) - 1.0) / 256.0
        with np.errstate(divide="ignore"):
            dd = np.where(codes > 1, baseline_m * fx / np.where(codes > 1, disparity, 1.0), np.inf)
        dd[codes == 0] = np.nan
        d = dd.astype(np.float32)
    elif fmt == "middlebury":
        f, doffs, baseline_mm = _middlebury_calib(Path(calib) if calib is not None else p.parent / "calib.txt")
        disp = read_pfm(p).astype(np.float64)
        valid = np.isfinite(disp)
        dd = np.full(disp.shape, np.nan)
        dd[valid] = baseline_mm * f / (disp[valid] + doffs) / 1000.0
        d = dd.astype(np.float32)
    elif fmt == "npy":
        a = np.load(p, allow_pickle=False)
        if a.ndim == 3 and a.shape[2] == 1:
            a = a[..., 0]
        if a.ndim != 2:
            raise ValueError(f"{p.name} holds an array of shape {a.shape}; a depth map is (H, W)")
        if a.dtype.kind in "iu":
            d = _scaled(a, depth_scale_m, p.name)
        elif a.dtype.kind == "f":
            if depth_scale_m is not None:
                raise ValueError(f"depth_scale_m applies to integer depth only: {p.name} holds float depth ({a.dtype}), metres already")
            d = np.ascontiguousarray(a, dtype=np.float32)
        else:
            raise ValueError(f"{p.name} holds {a.dtype}: a depth map is float metres or integer units")
    elif fmt == "exr":
        arr, names = _stored(p)
        if arr.dtype != np.float32:
            raise ValueError(f"{p.name} holds {arr.dtype} pixels: an EXR depth map is float metres")
        pick = next((names.index(n) for n in ("depth_m", "Z", "z", "depth") if n in names), 0 if arr.shape[2] == 1 else None)
        if pick is None:
            raise ValueError(f"{p.name} has channels {names}: a depth EXR needs one channel, or one named depth_m or Z")
        d = np.ascontiguousarray(arr[..., pick])
    else:  # scaled
        arr, _ = _stored(p)
        if arr.dtype == np.float32:
            if depth_scale_m is not None:
                raise ValueError(f"depth_scale_m applies to integer depth only: {p.name} holds float depth, metres already")
            d = np.ascontiguousarray(arr[..., 0])
        elif arr.dtype == np.uint8:
            raise ValueError(f"{p.name} is 8-bit: depth maps are 16-bit PNG or TIFF (with depth_scale_m), EXR, NPY or PFM")
        else:
            d = _scaled(arr[..., 0], depth_scale_m, p.name)
    if np.any(d < 0):  # NaN compares false
        at = tuple(int(v) for v in np.argwhere(d < 0)[0])
        raise ValueError(f"{p.name}: depth[{at[0]}, {at[1]}] = {d[at]} m is negative")
    return np.ascontiguousarray(d, dtype=np.float32)
