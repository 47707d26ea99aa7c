"""Where a photo shows sky, estimated from its pixels alone (no depth map, no network).

The estimator is classical and deliberately cautious: a pixel it calls sky is hazed by a
frame's weather along the whole path to the cloud base, so a wall taken for sky would lose its
texture. It follows two observations from the literature:

- sky is smooth: Shen & Wang, "Sky region detection in a single image for autonomous ground
  robot navigation" (International Journal of Advanced Robotic Systems, 2013) find it as the
  low-gradient region bounded by the first strong edges below the image's top;
- sky has the colours of sky: Zafarifar & de With, "Blue sky detection for picture quality
  enhancement" (ACIVS 2006) model clear skies as blue, brightest and smoothest toward the top.

The rule, at a working resolution of at most ``work_px`` on the long side (block means):

1. the gradient of the sRGB-coded luma (Sobel, per pixel), its largest value over each 3 x 3
   neighbourhood, below ``max_gradient``;
2. a sky colour: blue (B > R + 0.03 and B >= G - 0.02 in sRGB-coded values: clear, dusk and
   twilight skies) or bright and neutral (saturation (max - min)/max < 0.12 and linear
   luminance at least 0.8 of the photo's 99.5th percentile and above 0.2 of full scale: an
   overcast sky, the brightest thing in its photo);
3. the 4-connected regions of pixels meeting both that touch the image's top row and not
   its bottom row (a smooth region from top to bottom is a wall, a backdrop or a flat
   image, not a sky over anything); each must hold at least ``min_share`` of the image.

4. back at the photo's size, the regions are refined to the pixel: within ``BAND_BLOCKS``
   blocks of them, a pixel is sky where its colour lies within ``COLOUR_TOLERANCE`` of the
   sky's colour at its block (the regions' colours spread by a Gaussian of 2 blocks); so the mask
   follows a tower's edge instead of its blocks, takes in the sky seen through a lattice,
   and leaves out a star or a wire in the sky.

Studio backdrops and
bright walls that reach the top edge can pass rule 2 when they are the brightest, most
neutral thing in the photo; give ``PhotoScene(sky_mask=...)`` yourself where that matters.
Grey-scale photos have no colour to go by: only their bright neutral tops can be found.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import integer, real
from skyfall.io import decode_srgb, encode_srgb

__all__ = ["BAND_BLOCKS", "BLUE_MARGIN", "BRIGHT_SHARE", "COLOUR_TOLERANCE", "MAX_GRADIENT", "NEUTRAL_SATURATION", "estimate_sky_mask", "mask_iou"]

MAX_GRADIENT = 0.01
"""Default largest gradient of sRGB-coded luma (per working pixel, full scale 1) in sky."""
BLUE_MARGIN = 0.03
"""How much bluer than red (sRGB-coded, full scale 1) a blue sky pixel is at least."""
NEUTRAL_SATURATION = 0.12
"""Largest saturation, (max - min)/max of the sRGB-coded channels, of a bright neutral sky."""
COLOUR_TOLERANCE = 0.04
"""How far (largest channel difference, sRGB-coded, full scale 1) a pixel's colour may lie
from the sky's local colour to be refined into the sky mask."""
BAND_BLOCKS = 4
"""How far (working pixels) from the regions found the refinement looks for more sky."""
BRIGHT_SHARE = 0.8
"""A bright neutral sky's linear luminance over the photo's 99.5th percentile, at least."""
_LUMA = np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)


def check_encoding(encoding: Any) -> None:
    """Refuse an ``encoding`` that is not None, ``"srgb"`` or ``"linear"``, by name."""
    if encoding is not None and not (isinstance(encoding, str) and encoding in ("srgb", "linear")):
        raise ValueError(f"encoding = {encoding!r} must be None, 'srgb' or 'linear'")


def _coded(image: Any, encoding: str | None) -> tuple[NDArray[Any], float]:
    """The photo as sRGB-coded values: (uint8 codes, 255) or (float32 in [0, 1], 1)."""
    check_encoding(encoding)
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] not in (3, 4) or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"image must have shape (H, W, 3) or (H, W, 4), got {a.shape}")
    a = a[..., :3]
    if a.dtype == np.uint8:
        if encoding == "linear":
            raise ValueError("encoding = 'linear' does not fit a uint8 image: 8-bit images are sRGB codes")
        return a, 255.0
    if a.dtype.kind != "f":
        raise TypeError(f"image must be uint8 (sRGB codes) or float, got dtype {a.dtype}")
    f = a.astype(np.float32)
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise ValueError("image must hold finite values >= 0")
    if encoding == "srgb":
        return np.clip(f, 0.0, 1.0), 1.0
    if encoding != "linear":
        raise ValueError(f"encoding = {encoding!r}: a float image needs encoding='linear' or 'srgb'")
    # Linear light in any units: its 99.9th percentile taken as full scale, then encoded.
    top = float(np.quantile(f, 0.999))
    return np.asarray(encode_srgb(np.clip(f / top, 0.0, 1.0) if top > 0 else f), dtype=np.float32), 1.0


def _blocks(a: NDArray[Any], scale: float, k: int) -> NDArray[np.float64]:
    """Means over k x k blocks (the last partial row and column of blocks included), in [0, 1]."""
    h, w = a.shape[:2]
    hh, ww = math.ceil(h / k), math.ceil(w / k)
    pad = _padded(a, k)
    # summed along the block's rows first (uint16 holds k <= 257 codes), then its columns
    wide = np.uint16 if a.dtype == np.uint8 and k <= 257 else np.float64
    sums = pad.reshape(hh, k, ww, k, -1).sum(axis=1, dtype=wide).sum(axis=2, dtype=np.float64)
    out: NDArray[np.float64] = sums / (k * k * scale)
    return out


def _padded(a: NDArray[Any], k: int) -> NDArray[Any]:
    """``a`` padded at its bottom and right edges to whole k x k blocks."""
    h, w = a.shape[:2]
    hh, ww = math.ceil(h / k), math.ceil(w / k)
    if (hh * k, ww * k) == (h, w):
        return a
    return np.pad(a, ((0, hh * k - h), (0, ww * k - w), (0, 0)), mode="edge")


def estimate_sky_mask(
    image: Any,
    *,
    encoding: str | None = None,
    max_gradient: float = MAX_GRADIENT,
    min_share: float = 0.005,
    work_px: int = 256,
) -> NDArray[np.bool_]:
    """Estimate which pixels of a photo show sky (module docstring: the rule and its sources).

    Parameters
    ----------
    image : array_like, shape (H, W, 3) or (H, W, 4)
        uint8 sRGB codes, or floats with ``encoding`` (alpha, if any, is ignored).
    encoding : {"srgb", "linear"}, optional
        How float pixels are encoded (required for floats): ``"srgb"`` values in [0, 1], or
        ``"linear"`` light in any units (its 99.9th percentile is taken as full scale).
    max_gradient : float
        Largest sRGB-coded luma gradient per working pixel in sky, in (0, 1] (default 0.01).
    min_share : float
        Smallest share of the image a sky region holds, in [0, 1] (default 0.005).
    work_px : int
        Long side of the working resolution, px, in [16, 4096] (default 256).

    Returns
    -------
    ndarray of bool, shape (H, W)
        True where the photo shows sky.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((60, 80, 3), np.uint8)
    >>> img[:20] = (90, 140, 220)  # a clear sky over a ground of noise
    >>> img[20:] = np.random.default_rng(0).integers(0, 255, (40, 80, 3), dtype=np.uint8)
    >>> m = estimate_sky_mask(img)
    >>> bool(m[:15].all()), bool(m[25:].any())
    (True, False)
    """
    from scipy import ndimage as ndi  # type: ignore[import-untyped]

    g_max = real("max_gradient", max_gradient)
    if not 0.0 < g_max <= 1.0:
        raise ValueError(f"max_gradient = {g_max} is outside the valid range (0, 1]")
    share = real("min_share", min_share)
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"min_share = {share} is outside the valid range [0, 1]")
    work = integer("work_px", work_px, 16, 4096)
    coded, scale = _coded(image, encoding)
    h, w = coded.shape[:2]
    k = max(1, math.ceil(max(h, w) / work))
    a = _blocks(coded, scale, k)
    luma = a @ _LUMA
    grad = np.hypot(ndi.sobel(luma, axis=1), ndi.sobel(luma, axis=0)) / 8.0
    smooth = ndi.maximum_filter(grad, size=3, mode="nearest") < g_max
    r, g, b = a[..., 0], a[..., 1], a[..., 2]
    blue = (b > r + BLUE_MARGIN) & (b >= g - 0.02)
    hi, lo = a.max(axis=2), a.min(axis=2)
    saturation = (hi - lo) / np.maximum(hi, 1e-6)
    y = np.asarray(decode_srgb(a.astype(np.float32)), dtype=np.float64) @ _LUMA
    bright = (saturation < NEUTRAL_SATURATION) & (y >= BRIGHT_SHARE * float(np.quantile(y, 0.995))) & (y > 0.2)
    labels, _ = ndi.label(smooth & (blue | bright))
    top = np.setdiff1d(np.unique(labels[0]), np.unique(labels[-1]))
    top = top[top > 0]
    if top.size:
        sizes = np.bincount(labels.ravel())
        top = top[sizes[top] * k * k >= share * h * w]
    small = np.isin(labels, top)
    if not small.any():
        return np.zeros((h, w), dtype=bool)
    return _refine(coded, scale, a, small, k)


def _up(small: NDArray[Any], k: int, h: int, w: int) -> NDArray[Any]:
    return np.repeat(np.repeat(small, k, axis=0), k, axis=1)[:h, :w]


def _refine(coded: NDArray[Any], scale: float, blocks: NDArray[np.float64], small: NDArray[np.bool_], k: int) -> NDArray[np.bool_]:
    """The block mask refined to the pixel (rule 4 of the module docstring)."""
    from scipy import ndimage as ndi

    h, w = coded.shape[:2]
    weight = ndi.gaussian_filter(small.astype(np.float64), 2.0, mode="nearest")
    colour = np.stack([ndi.gaussian_filter(blocks[..., c] * small, 2.0, mode="nearest") for c in range(3)], axis=-1)
    colour /= np.maximum(weight, 1e-6)[..., None]
    band = ndi.binary_dilation(small, iterations=BAND_BLOCKS) & (weight > 0.02)
    hh, ww = small.shape
    pad = _padded(coded, k).reshape(hh, k, ww, k, 3)
    if coded.dtype == np.uint8:  # in codes: the tolerance is COLOUR_TOLERANCE * 255
        local = np.round(colour * 255.0).astype(np.int16)[:, None, :, None, :]
        diff = np.abs(pad.astype(np.int16) - local)
        tol: float = COLOUR_TOLERANCE * 255.0
    else:
        diff = np.abs(pad - colour.astype(np.float32)[:, None, :, None, :])
        tol = COLOUR_TOLERANCE
    near = np.maximum(np.maximum(diff[..., 0], diff[..., 1]), diff[..., 2]) < tol
    near &= band[:, None, :, None]
    return np.ascontiguousarray(near.reshape(hh * k, ww * k)[:h, :w])


def mask_iou(a: Any, b: Any) -> float:
    """Intersection over union of two boolean masks of one shape (1.0 when both are empty).

    Examples
    --------
    >>> mask_iou([[True, True], [False, False]], [[True, False], [False, False]])
    0.5
    """
    x, y = np.asarray(a, dtype=bool), np.asarray(b, dtype=bool)
    if x.shape != y.shape:
        raise ValueError(f"the masks' shapes differ: {x.shape} and {y.shape}")
    union = int(np.count_nonzero(x | y))
    return 1.0 if union == 0 else int(np.count_nonzero(x & y)) / union
