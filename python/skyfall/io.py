"""Image files through OpenImageIO.

Float formats (EXR) keep linear float32 values and any number of named channels exactly.
8-bit formats (PNG, JPEG, TIFF-8) hold sRGB-encoded values: :func:`write_image` encodes
linear input with the sRGB transfer function (IEC 61966-2-1) and :func:`read_image` decodes
it back to linear float32. Depth maps in the formats users have (KITTI, Cityscapes,
Middlebury, EXR, NPY, scaled 16-bit) are read by :func:`read_depth` (:mod:`skyfall.depth_io`). An alpha channel (named ``A``) is stored unencoded and
unassociated (``oiio:UnassociatedAlpha``), so it round-trips without OIIO
un-premultiplying colour.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import values
from skyfall.depth_io import DEPTH_FORMATS, read_depth

__all__ = [
    "DEPTH_FORMATS",
    "decode_srgb",
    "decode_srgb8",
    "encode_srgb",
    "read_channels",
    "read_depth",
    "read_image",
    "read_image_with_metadata",
    "read_stored",
    "srgb8_table",
    "to_srgb8",
    "write_image",
]

_FLOAT_EXTS = {".exr", ".hdr", ".tif", ".tiff", ".pfm"}
_DEFAULT_NAMES = {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}


def encode_srgb(linear: Any) -> NDArray[np.float32]:
    """sRGB transfer function (IEC 61966-2-1): linear [0, 1] to encoded [0, 1].

    12.92 x for x <= 0.0031308, 1.055 x^(1/2.4) - 0.055 above; input is clipped to [0, 1].
    NaN is refused (ValueError naming ``linear``), as :func:`to_srgb8` refuses it.

    Examples
    --------
    >>> np.round(encode_srgb([0.0, 0.214, 1.0, 2.0]), 3)  # linear 0.214 is mid-grey
    array([0. , 0.5, 1. , 1. ], dtype=float32)
    """
    x: NDArray[np.float32] = np.clip(values("linear", linear), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055).astype(np.float32)


def decode_srgb(encoded: Any) -> NDArray[np.float32]:
    """Inverse sRGB transfer function: encoded [0, 1] to linear [0, 1] (clipped); NaN is
    refused (ValueError naming ``encoded``).

    Examples
    --------
    >>> np.round(decode_srgb([0.0, 0.5, 1.0]), 3)
    array([0.   , 0.214, 1.   ], dtype=float32)
    """
    v: NDArray[np.float32] = np.clip(values("encoded", encoded), 0.0, 1.0)
    return np.where(v <= 0.04045, v / 12.92, np.power((v + 0.055) / 1.055, 2.4)).astype(np.float32)


_SRGB8_TO_LINEAR = None


def srgb8_table() -> NDArray[np.float32]:
    """The 256 linear values of the 8-bit sRGB codes (:func:`decode_srgb` of ``k / 255``)."""
    global _SRGB8_TO_LINEAR
    if _SRGB8_TO_LINEAR is None:
        _SRGB8_TO_LINEAR = decode_srgb(np.arange(256, dtype=np.float32) / np.float32(255.0))
    table: NDArray[np.float32] = _SRGB8_TO_LINEAR
    return table


def decode_srgb8(encoded: Any) -> NDArray[np.float32]:
    """Decode 8-bit sRGB to linear float32 through a 256-entry table (same values as
    :func:`decode_srgb` of ``encoded / 255``), in Rust, in parallel.

    Raises
    ------
    ValueError
        When a value is not a whole number in [0, 255] (it would wrap around as a byte).

    Examples
    --------
    >>> np.round(decode_srgb8(np.array([0, 128, 255], np.uint8)), 4)
    array([0.    , 0.2159, 1.    ], dtype=float32)
    """
    arr = np.asarray(encoded)
    if arr.dtype != np.uint8:
        if arr.dtype.kind not in "fiub":
            raise TypeError(f"encoded must hold 8-bit codes, got dtype {arr.dtype}")
        bad = ~((arr >= 0) & (arr <= 255) & (arr == np.round(arr)))
        if np.any(bad):
            first = arr.reshape(-1)[int(np.argmax(bad.reshape(-1)))]
            raise ValueError(f"encoded holds {first!r}, which is not an 8-bit code (a whole number in [0, 255])")
    return _core.apply_lut8(np.ascontiguousarray(arr, dtype=np.uint8), srgb8_table())


def to_srgb8(linear: Any, *, alpha_channel: int | None = None) -> NDArray[np.uint8]:
    """Encode linear values to 8-bit sRGB (rounded to nearest, in Rust, in parallel);
    values are clipped to [0, 1]; an alpha channel stays linear.

    Raises
    ------
    ValueError
        For NaN anywhere in ``linear`` (8-bit sRGB has no NaN; :func:`write_image` refuses
        it too): replace it first (``np.nan_to_num``).

    Examples
    --------
    >>> to_srgb8([0.0, 0.214, 1.0, 2.0])
    array([  0, 127, 255, 255], dtype=uint8)
    >>> to_srgb8([[0.214, 0.214, 0.214, 0.5]], alpha_channel=3)  # alpha: 0.5 * 255, rounded
    array([[127, 127, 127, 128]], dtype=uint8)
    """
    arr = values("linear", linear, nan=True)  # NaN: refused by the encoder, with the count
    out: NDArray[np.uint8] = _core.encode_srgb8(arr)
    if alpha_channel is not None:
        out[..., alpha_channel] = np.rint(np.clip(arr[..., alpha_channel], 0.0, 1.0) * 255.0).astype(np.uint8)
    return out


def _as_hwc(image: Any) -> NDArray[Any]:
    arr = np.asarray(image)
    if arr.ndim == 2:
        arr = arr[:, :, None]
    if arr.ndim != 3 or arr.shape[0] == 0 or arr.shape[1] == 0 or arr.shape[2] == 0:
        raise ValueError(f"image must have shape (H, W) or (H, W, C) with H, W, C >= 1, got {arr.shape}")
    if arr.dtype.kind not in "fui":
        raise TypeError(f"image must be numeric, got dtype {arr.dtype}")
    return arr


def _codes(p: Path, arr: NDArray[Any]) -> str:
    """What an 8-bit (or PNG 16-bit) file stores of ``arr``: "uint8" or "uint16"; integer types
    that are not codes, and NaN, are refused."""
    if arr.dtype == np.uint16 and p.suffix.lower() == ".png":
        return "uint16"
    if arr.dtype.kind in "iub" and arr.dtype != np.uint8:
        hint = " (PNG stores uint16 as it is)" if arr.dtype == np.uint16 else ""
        raise TypeError(
            f"image has dtype {arr.dtype}: an {p.suffix or 'image'} file stores uint8 codes{hint}; pass uint8 codes, "
            "or floats (encoded as sRGB, or with encoding='linear' as data)"
        )
    if arr.dtype.kind == "f":
        nan = int(np.count_nonzero(np.isnan(arr)))
        if nan:
            raise ValueError(f"image holds {nan} NaN values, which an 8-bit file cannot store: replace them (np.nan_to_num) or write EXR")
    return "uint8"


def write_image(
    path: str | Path,
    image: Any,
    *,
    channel_names: Sequence[str] | None = None,
    metadata: Mapping[str, str | int | float] | None = None,
    encoding: str = "srgb",
) -> None:
    """Write an image file; the format follows the extension.

    Parameters
    ----------
    path : str or Path
        Output file. ``.exr`` (and other float formats) store float32 as given; ``.png``,
        ``.jpg`` store 8-bit codes (uint8 input is written as it is; float input is encoded as
        ``encoding`` says); ``.png`` also stores uint16 input as 16-bit codes, as it is.
    image : array_like, shape (H, W) or (H, W, C)
        Linear values (float), or codes (uint8; uint16 for PNG). Other integer types are refused:
        their range says nothing of how to encode them.
    channel_names : sequence of str, optional
        One name per channel; defaults to Y, Y/A, R/G/B, R/G/B/A, else C0, C1, ...
    metadata : mapping, optional
        Extra attributes stored in the file header.
    encoding : {"srgb", "linear"}
        How float input becomes 8-bit codes: ``"srgb"`` (default) encodes linear light for
        viewing; ``"linear"`` stores data as it is, ``round(255 * clip(x, 0, 1))``, for masks and
        data layers (``rain_alpha``, ``transmittance``).

    Raises
    ------
    TypeError
        For integer input other than uint8 (and uint16 into PNG).
    ValueError
        For NaN in float input to an 8-bit file (it has no NaN), or an unknown ``encoding``.
    OSError
        When OpenImageIO cannot create or write the file.
    """
    import OpenImageIO as oiio

    arr = _as_hwc(image)
    h, w, c = arr.shape
    names = list(channel_names) if channel_names is not None else _DEFAULT_NAMES.get(c, [f"C{i}" for i in range(c)])
    if len(names) != c:
        raise ValueError(f"channel_names has {len(names)} names for {c} channels")
    p = Path(path)
    is_float = p.suffix.lower() in _FLOAT_EXTS
    alpha = names.index("A") if "A" in names else None
    if encoding not in ("srgb", "linear"):
        raise ValueError(f"encoding = {encoding!r} must be \"srgb\" or \"linear\"")
    if is_float:
        data: NDArray[Any] = np.ascontiguousarray(arr, dtype=np.float32)
        spec = oiio.ImageSpec(w, h, c, "float")
        spec.attribute("compression", "zip")
    else:
        kind = _codes(p, arr)
        if kind == "uint16":
            data, spec = np.ascontiguousarray(arr), oiio.ImageSpec(w, h, c, "uint16")
        else:
            if arr.dtype == np.uint8:
                data = np.ascontiguousarray(arr)
            elif encoding == "linear":
                data = np.rint(np.clip(arr.astype(np.float32), 0.0, 1.0) * 255.0).astype(np.uint8)
            else:
                data = to_srgb8(arr, alpha_channel=alpha)
            spec = oiio.ImageSpec(w, h, c, "uint8")
        if arr.dtype == np.uint8 or (arr.dtype.kind == "f" and encoding == "srgb"):
            spec.attribute("oiio:ColorSpace", "sRGB")
        if alpha is not None:
            spec.alpha_channel = alpha
            spec.attribute("oiio:UnassociatedAlpha", 1)
    spec.channelnames = tuple(names)
    for key, value in (metadata or {}).items():
        spec.attribute(key, value)
    out = oiio.ImageOutput.create(str(p))
    if out is None:
        raise OSError(f"cannot write {p}: {oiio.geterror()}")
    try:
        if not out.open(str(p), spec) or not out.write_image(data):
            raise OSError(f"cannot write {p}: {out.geterror()}")
    finally:
        out.close()


def read_stored(path: str | Path) -> tuple[NDArray[Any], dict[str, Any]]:
    """Read an image's pixels as the file stores them, (H, W, C): uint8 or uint16 codes, or
    float32 for float files (half and double converted), with its header attributes
    (``channel_names`` and ``alpha_channel``, -1 for none, among them).

    Raises
    ------
    OSError
        When OpenImageIO cannot read the file.
    """
    import OpenImageIO as oiio

    p = Path(path)
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    inp = oiio.ImageInput.open(str(p), config)
    if inp is None:
        raise OSError(f"cannot read {p}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        base = spec.format.basetype
        kind = "uint8" if base == oiio.UINT8 else "uint16" if base == oiio.UINT16 else "float"
        raw = inp.read_image(kind)
        if raw is None:
            raise OSError(f"cannot read {p}: {inp.geterror()}")
    finally:
        inp.close()
    arr = np.asarray(raw).reshape(spec.height, spec.width, spec.nchannels)
    meta: dict[str, Any] = {a.name: a.value for a in spec.extra_attribs}
    meta["channel_names"] = list(spec.channelnames)
    meta["alpha_channel"] = int(spec.alpha_channel)
    return (np.ascontiguousarray(arr, dtype=np.float32) if kind == "float" else arr), meta


def read_image_with_metadata(path: str | Path) -> tuple[NDArray[np.float32], dict[str, Any]]:
    """Read an image as linear float32 (H, W, C) with its header attributes.

    8-bit and 16-bit files are decoded from sRGB (alpha excepted, scaled to [0, 1]); float
    files are returned as stored. The attributes include ``channel_names``
    (:func:`read_stored`).
    """
    arr, meta = read_stored(path)
    if arr.dtype == np.float32:
        return arr, meta
    full = 255.0 if arr.dtype == np.uint8 else 65535.0
    lin = decode_srgb8(arr) if arr.dtype == np.uint8 else decode_srgb(arr.astype(np.float32) / np.float32(full))
    a = meta["alpha_channel"]
    if a >= 0:
        lin[..., a] = arr[..., a].astype(np.float32) / np.float32(full)
    return lin, meta


def read_image(path: str | Path) -> NDArray[np.float32]:
    """Read an image as linear float32, shape (H, W, C); see :func:`read_image_with_metadata`."""
    return read_image_with_metadata(path)[0]


def read_channels(path: str | Path) -> dict[str, NDArray[np.float32]]:
    """Read every channel of an image by name, e.g. a frame saved as EXR.

    OpenEXR stores channels sorted by name, so look them up by name rather than position:
    ``read_channels("frame.exr")["rain_alpha"]``.

    Returns
    -------
    dict of str to ndarray of float32, shape (H, W)
    """
    data, meta = read_image_with_metadata(path)
    return {name: np.ascontiguousarray(data[..., i]) for i, name in enumerate(meta["channel_names"])}
