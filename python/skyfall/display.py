"""Frames as pictures for Jupyter: PNG bytes and a small HTML table of a frame's layers.

PNG files are written through :mod:`skyfall.io` (OpenImageIO, the ``io`` extra) and read back
as bytes; nothing here is on a hot path (a 320 x 180 frame takes about 10 ms, written and read back).
"""

from __future__ import annotations

import base64
import html
import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from skyfall import io

if TYPE_CHECKING:
    from skyfall.render import Frame

__all__ = ["THUMBNAIL_PX", "frame_html", "layer_preview", "png_bytes"]

THUMBNAIL_PX = 256
"""The longer side of the pictures :func:`frame_html` shows, px (larger frames are subsampled)."""


def png_bytes(image: Any) -> bytes:
    """Encode an image as PNG bytes.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, C)
        uint8 codes (written as they are), or floats (linear light, sRGB-encoded; as
        :func:`skyfall.io.write_image` does).

    Returns
    -------
    bytes
        The PNG file's bytes.
    """
    with tempfile.TemporaryDirectory(prefix="skyfall-png-") as folder:
        path = Path(folder) / "image.png"
        io.write_image(path, image)
        return path.read_bytes()


def layer_preview(name: str, values: NDArray[np.float32]) -> NDArray[np.uint8]:
    """A layer as an 8-bit grey picture: values in [0, 1] as data (``round(255 x)``), and a
    distance layer (its name ends in ``_m``) as 1 / (1 + d / 1 m), so near is bright and
    inf (none) is black.

    Parameters
    ----------
    name : str
        The layer's name (``skyfall._core.LAYERS``).
    values : ndarray of float32, shape (H, W)
        The layer.

    Returns
    -------
    ndarray of uint8, shape (H, W)
    """
    v = np.asarray(values, dtype=np.float32)
    if name.endswith("_m"):
        v = (1.0 / (1.0 + np.maximum(v, 0.0))).astype(np.float32)
    out: NDArray[np.uint8] = np.rint(np.clip(np.nan_to_num(v, nan=0.0), 0.0, 1.0) * 255.0).astype(np.uint8)
    return out


def _thumbnail(image: NDArray[Any]) -> NDArray[Any]:
    """``image`` subsampled by a whole stride so its longer side is at most THUMBNAIL_PX."""
    step = max(1, math.ceil(max(image.shape[0], image.shape[1]) / THUMBNAIL_PX))
    return image[::step, ::step]


def _img_tag(image: NDArray[Any], caption: str) -> str:
    data = base64.b64encode(png_bytes(_thumbnail(image))).decode("ascii")
    return (
        '<figure style="display:inline-block;margin:0 6px 6px 0;text-align:center">'
        f'<img src="data:image/png;base64,{data}" style="image-rendering:pixelated"/>'
        f'<figcaption style="font-size:small">{html.escape(caption)}</figcaption></figure>'
    )


def frame_html(frame: Frame) -> str:
    """The frame's sRGB image (``io.to_srgb8(frame.rgb)``) and each layer it drew, side by
    side as small base64 PNGs (longer side at most :data:`THUMBNAIL_PX`).

    Parameters
    ----------
    frame : skyfall.Frame

    Returns
    -------
    str
        An HTML fragment.
    """
    h, w = frame.depth_m.shape
    parts = [_img_tag(io.to_srgb8(frame.rgb), f"rgb, {w}x{h} ({frame.backend})")]
    for name, values in frame.layers.items():
        how = "1/(1+d)" if name.endswith("_m") else "0-1"
        parts.append(_img_tag(layer_preview(name, values), f"{name} ({how})"))
    return '<div class="skyfall-frame">' + "".join(parts) + "</div>"
