"""A dataset's files: reading photos and depth maps, atomic writes, checksums.

Every output is written under a temporary name in its own folder (``.NAME.tmp-PID.EXT``) and
then renamed onto its final name with :func:`os.replace`, so a run killed at any moment
(``kill -9`` included) leaves under a final name only complete files; the temporary ones are
removed when the run is resumed.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall import io

__all__ = [
    "IMAGE_EXTENSIONS",
    "DEPTH_EXTENSIONS",
    "NpyStack",
    "atomic_write",
    "find_depth",
    "list_images",
    "read_depth",
    "read_photo",
    "remove_temporaries",
    "sha256_file",
    "write_json",
    "write_npy",
    "write_png",
]

IMAGE_EXTENSIONS = frozenset({".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".bmp", ".tga", ".webp", ".hdr", ".dpx", ".ppm", ".pgm"})
"""The photo file extensions an input folder is scanned for (read through OpenImageIO)."""
DEPTH_EXTENSIONS = (".exr", ".npy", ".png", ".tif", ".tiff", ".pfm")
"""Depth map extensions, in the order a stem is looked up in."""
TMP_MARK = ".tmp-"


def list_images(folder: Path) -> list[Path]:
    """The photos in ``folder`` (not its sub-folders, no hidden files), in name order.

    Raises
    ------
    FileNotFoundError
        When ``folder`` is not a folder.
    """
    if not folder.is_dir():
        raise FileNotFoundError(f"input = {str(folder)!r} is not a folder")
    return sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".") and p.suffix.lower() in IMAGE_EXTENSIONS)


def find_depth(folder: Path, stem: str) -> Path | None:
    """The depth map of the photo named ``stem`` in ``folder`` (first of DEPTH_EXTENSIONS), or None."""
    for ext in DEPTH_EXTENSIONS:
        p = folder / f"{stem}{ext}"
        if p.is_file():
            return p
    return None


def read_photo(path: Path, *, with_metadata: bool = False) -> Any:
    """A photo for :class:`skyfall.PhotoScene`: (image, encoding), and its header attributes
    (EXIF among them) as a third item with ``with_metadata``.

    8-bit files come back as their uint8 sRGB codes (encoding None: the fused 8-bit path),
    16-bit files as sRGB-encoded floats in [0, 1] ("srgb"), float files (EXR, HDR) as linear
    floats ("linear"). Grey images are repeated into RGB; an alpha channel is dropped (the
    dataset's rows say so: ``alpha_dropped``).

    Raises
    ------
    OSError
        When OpenImageIO cannot read the file.
    ValueError
        For an image with 2 or more than 4 channels.
    """
    arr, meta = io.read_stored(path)
    kind = "float" if arr.dtype == np.float32 else str(arr.dtype)
    c = arr.shape[2]
    if c in (1, 2):
        arr = np.repeat(arr[..., :1], 3, axis=2)
    elif c in (3, 4):
        arr = arr[..., :3]
    else:
        raise ValueError(f"{path.name} has {c} channels; a photo has 1 (grey), 3 (RGB) or 4 (RGBA)")
    arr = np.ascontiguousarray(arr)
    meta["alpha_dropped"] = c in (2, 4)
    if kind == "uint8":
        image, encoding = arr, None
    elif kind == "uint16":
        image, encoding = (arr.astype(np.float32) / np.float32(65535.0)), "srgb"
    else:
        image, encoding = arr.astype(np.float32), "linear"
    return (image, encoding, meta) if with_metadata else (image, encoding)


def read_depth(path: Path, depth_scale_m: float | None, depth_format: str | None = None) -> NDArray[np.float32]:
    """A depth map for :class:`skyfall.PhotoScene`, float32 metres (``inf`` sky, ``NaN`` no
    data): :func:`skyfall.io.read_depth` with the dataset's options. For ``"cityscapes"`` the
    camera file is ``STEM.json`` beside the depth map, for ``"middlebury"`` the calibration
    ``STEM.txt`` beside it or else ``calib.txt``.

    Raises
    ------
    ValueError, FileNotFoundError, OSError
        As :func:`skyfall.io.read_depth`.
    """
    from skyfall.depth_io import format_for
    from skyfall.depth_io import read_depth as read

    fmt = depth_format if depth_format is not None else format_for(path)
    extra: dict[str, Any] = {}
    if fmt == "cityscapes":
        extra["camera_json"] = path.with_suffix(".json")
    elif fmt == "middlebury":
        own = path.with_suffix(".txt")
        extra["calib"] = own if own.is_file() else path.parent / "calib.txt"
    return read(path, fmt, depth_scale_m=depth_scale_m, **extra)

def sha256_file(path: Path) -> str:
    """The sha256 of a file's bytes, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _tmp_name(final: Path) -> Path:
    # the extension kept last: OpenImageIO picks the format by it
    return final.with_name(f".{final.name}{TMP_MARK}{os.getpid()}{final.suffix}")


def atomic_write(final: Path, write: Callable[[Path], None]) -> str:
    """Write ``final`` through ``write(tmp)`` on a temporary name beside it, then rename.

    Returns
    -------
    str
        The sha256 of the file written (read back from the temporary file before the rename).
    """
    tmp = _tmp_name(final)
    try:
        write(tmp)
        digest = sha256_file(tmp)
        os.replace(tmp, final)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return digest


PNG_FILTER_SUB = 16
"""libpng's PNG_FILTER_SUB, OpenImageIO's ``png:filter`` for the dataset's PNGs: at 1080p and zlib
level 1 a rainy, hazy photo is written in 76 ms against 149 ms with libpng's default adaptive
filters, 2 % larger (3.48 against 3.42 MB); see benches/results/dataset.md."""


def write_png(final: Path, image: NDArray[Any], compression: int, strategy: str = "default") -> str:
    """An 8-bit PNG at zlib level ``compression`` (``png:compressionLevel``) and zlib strategy
    ``strategy`` (OpenImageIO's ``compression``: default, huffman, rle, filtered) with the SUB
    filter, atomically; its sha256."""
    meta: dict[str, str | int] = {"png:compressionLevel": compression, "png:filter": PNG_FILTER_SUB, "compression": strategy}
    return atomic_write(final, lambda p: io.write_image(p, image, metadata=meta))


def write_npy(final: Path, array: NDArray[Any]) -> str:
    """A ``.npy`` file, atomically; its sha256."""

    def save(p: Path) -> None:
        with open(p, "wb") as f:
            np.save(f, np.ascontiguousarray(array), allow_pickle=False)

    return atomic_write(final, save)


class NpyStack:
    """A float32 ``.npy`` file of ``shape`` filled in place (a memory map of its temporary file,
    so a clip's (N, H, W) layer stack is not held in memory), then renamed onto ``final``.

    The bytes are those :func:`write_npy` writes for the same array (``np.save``'s header).

    Parameters
    ----------
    final : Path
        The file's final name.
    shape : tuple of int
        The array's shape, e.g. (frames, height px, width px).
    """

    def __init__(self, final: Path, shape: tuple[int, ...]) -> None:
        self.final = final
        self.tmp = _tmp_name(final)
        self.array: NDArray[np.float32] = np.lib.format.open_memmap(self.tmp, mode="w+", dtype=np.float32, shape=shape)

    def commit(self) -> str:
        """Flush the array, rename the file onto its final name; its sha256."""
        mm: Any = self.array
        mm.flush()
        del mm
        self.array = np.empty((0,), np.float32)  # the map released before the rename
        digest = sha256_file(self.tmp)
        os.replace(self.tmp, self.final)
        return digest

    def discard(self) -> None:
        """Remove the temporary file (an item that failed)."""
        self.array = np.empty((0,), np.float32)
        self.tmp.unlink(missing_ok=True)


def write_json(final: Path, obj: Any) -> str:
    """A JSON file (sorted keys, one line per object for a list), atomically; its sha256."""
    if isinstance(obj, list):
        text = "".join(json.dumps(o, sort_keys=True) + "\n" for o in obj)
    else:
        text = json.dumps(obj, sort_keys=True, indent=1) + "\n"
    def save(p: Path) -> None:
        p.write_text(text)

    return atomic_write(final, save)


def remove_temporaries(folder: Path) -> int:
    """Remove what a killed run left under temporary names in ``folder``; how many."""
    n = 0
    if folder.is_dir():
        for p in folder.iterdir():
            if p.name.startswith(".") and TMP_MARK in p.name:
                p.unlink(missing_ok=True)
                n += 1
    return n
