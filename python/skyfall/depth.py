"""Depth for photos that come without it: a monocular network through onnxruntime, and its
relative output turned into metres by a documented rule.

Install the extra: ``pip install 'skyfall[depth]'`` (onnxruntime and huggingface_hub).

The default network is Depth Anything V2 Small (Yang et al., "Depth Anything V2", 2024;
Apache-2.0), as the ONNX export ``onnx-community/depth-anything-v2-small`` (``onnx/model.onnx``,
99 MB), downloaded on first use through huggingface_hub into :func:`cache_dir` and read from
there afterwards (offline too). Any ONNX file with one image input (1, 3, h, w) and one
output (1, h, w) or (1, 1, h, w), or any Python callable, can stand in for it.

**What a network gives.** Depth Anything (like MiDaS) predicts *affine-invariant inverse
depth*: r = s / Z + t for unknown s > 0 and t. :func:`to_metres` recovers s and t:

- ``camera_height_m`` / ``horizon_row`` (a level ground below the horizon): s and t fitted by
  least squares between r and the ground plane's 1 / Z over the ground pixels (the lowest
  ``GROUND_SHARE`` of the rows below the horizon), trimmed three times of the pixels whose
  residual exceeds 3 median absolute deviations (cars, kerbs, people);
- ``distance_m`` alone: t = 0 (the network's sky, infinitely far, is at r = 0) and s such that
  the median pixel outside the sky lies at ``distance_m``;
- both: the ground's equations and the median's (over the pixels the ground's fit puts at
  a finite distance), the median weighted as all the ground pixels together.

Where r - t <= 0 the pixel is sky (``inf``).
"""

from __future__ import annotations

import math
import os
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import in_range, integer
from skyfall.camera import Camera

__all__ = ["GROUND_SHARE", "MODELS", "ModelSpec", "cache_dir", "estimate", "relative_inverse_depth", "to_metres"]

GROUND_SHARE = 0.3
"""The share of the rows below the horizon, lowest first, taken as ground for the fit."""
_MEAN = np.array([0.485, 0.456, 0.406], dtype=np.float32)
_STD = np.array([0.229, 0.224, 0.225], dtype=np.float32)


@dataclass(frozen=True)
class ModelSpec:
    """A downloadable network: its Hugging Face repository and file, input size and licence."""

    repo_id: str
    filename: str
    input_px: int
    multiple_px: int
    licence: str


MODELS: dict[str, ModelSpec] = {
    "depth-anything-v2-small": ModelSpec("onnx-community/depth-anything-v2-small", "onnx/model.onnx", 518, 14, "Apache-2.0"),
}
"""The networks :func:`estimate` can download by name."""


def cache_dir() -> Path:
    """Where downloaded networks are kept: ``$SKYFALL_CACHE/models``, else
    ``~/.cache/skyfall/models``."""
    root = os.environ.get("SKYFALL_CACHE")
    return (Path(root) if root else Path.home() / ".cache" / "skyfall") / "models"


def _model_path(name: str) -> Path:
    spec = MODELS[name]
    where = cache_dir()
    hint = (
        f"the depth network {name!r} ({spec.repo_id}/{spec.filename}, {spec.licence}) is not in the cache "
        f"folder {where} and could not be downloaded"
    )
    try:
        from huggingface_hub import hf_hub_download
    except ImportError:
        raise ImportError(f"{hint}: install the extra, pip install 'skyfall[depth]' (huggingface_hub), or pass model= an ONNX file") from None
    try:
        return Path(hf_hub_download(spec.repo_id, spec.filename, cache_dir=str(where)))
    except Exception as exc:  # offline, no such file, no network: one message that says what to do
        raise OSError(
            f"{hint} ({type(exc).__name__}). Connect once to download it, or put the ONNX file somewhere "
            "and pass model='path/to/model.onnx'; the extra is skyfall[depth]"
        ) from exc


_SESSIONS: OrderedDict[tuple[str, int], Any] = OrderedDict()
_SESSIONS_KEPT = 2


def _session(path: Path, threads: int) -> Any:
    """An onnxruntime session for ``path`` (the last two are kept)."""
    try:
        import onnxruntime as ort  # type: ignore[import-untyped]
    except ImportError:
        raise ImportError("depth estimation runs ONNX networks through onnxruntime: pip install 'skyfall[depth]'") from None
    key = (str(path.resolve()), threads)
    if key in _SESSIONS:
        _SESSIONS.move_to_end(key)
        return _SESSIONS[key]
    if not path.is_file():
        raise FileNotFoundError(f"model = {str(path)!r} is not a file")
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads  # a fixed thread count: the same bits every run
    opts.inter_op_num_threads = 1
    opts.log_severity_level = 3
    session = ort.InferenceSession(str(path), sess_options=opts, providers=["CPUExecutionProvider"])
    _SESSIONS[key] = session
    while len(_SESSIONS) > _SESSIONS_KEPT:
        _SESSIONS.popitem(last=False)
    return session


def _resize(a: NDArray[np.float32], shape: tuple[int, int]) -> NDArray[np.float32]:
    """Bilinear resampling of (h, w) or (h, w, c) to ``shape``, pixel centres aligned."""
    from scipy import ndimage as ndi  # type: ignore[import-untyped]

    h, w = a.shape[:2]
    ys = (np.arange(shape[0], dtype=np.float64) + 0.5) * (h / shape[0]) - 0.5
    xs = (np.arange(shape[1], dtype=np.float64) + 0.5) * (w / shape[1]) - 0.5
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    if a.ndim == 2:
        out: NDArray[np.float32] = np.asarray(ndi.map_coordinates(a, [yy, xx], order=1, mode="nearest"), dtype=np.float32)
        return out
    return np.stack([ndi.map_coordinates(a[..., c], [yy, xx], order=1, mode="nearest") for c in range(a.shape[2])], axis=-1).astype(np.float32)


def _coded(image: Any) -> NDArray[np.float32]:
    """The photo as sRGB-coded float32 in [0, 1], (H, W, 3)."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] not in (3, 4) or a.shape[0] < 2 or a.shape[1] < 2:
        raise ValueError(f"image must have shape (H, W, 3) or (H, W, 4) with H, W >= 2, got {a.shape}")
    a = a[..., :3]
    if a.dtype == np.uint8:
        return a.astype(np.float32) / np.float32(255.0)
    if a.dtype.kind != "f":
        raise TypeError(f"image must be uint8 sRGB codes or sRGB-encoded floats in [0, 1], got dtype {a.dtype}")
    f = a.astype(np.float32)
    if not np.all((f >= 0.0) & (f <= 1.0)):
        raise ValueError("image: float pixels must be sRGB-encoded values in [0, 1] (NaN included in the check)")
    return f


def relative_inverse_depth(image: Any, *, model: Any = "depth-anything-v2-small", threads: int = 1) -> NDArray[np.float32]:
    """A network's relative inverse depth for a photo, at the photo's size.

    Parameters
    ----------
    image : array_like, shape (H, W, 3) or (H, W, 4)
        uint8 sRGB codes, or sRGB-encoded floats in [0, 1].
    model : str, path or callable
        A name in :data:`MODELS` (downloaded on first use), an ONNX file, or a callable taking
        the sRGB-coded float32 (H, W, 3) photo and returning an (h, w) map (resized to the
        photo bilinearly).
    threads : int
        onnxruntime's intra-op threads, in [1, 256] (default 1: bit-for-bit the same every run).

    Returns
    -------
    ndarray of float32, shape (H, W)
        Larger is nearer; affine-invariant (see :func:`to_metres`).
    """
    coded = _coded(image)
    h, w = coded.shape[:2]
    if callable(model):
        out = np.asarray(model(coded), dtype=np.float32)
        if out.ndim != 2 or out.size == 0:
            raise ValueError(f"the model callable returned shape {out.shape}; it must return a 2-D (h, w) map")
    else:
        n = integer("threads", threads, 1, 256)
        if isinstance(model, str) and model in MODELS:
            spec = MODELS[model]
            path, side, mult = _model_path(model), spec.input_px, spec.multiple_px
        elif isinstance(model, (str, os.PathLike)):
            path, side, mult = Path(model), 518, 14
        else:
            raise TypeError(f"model must be one of {list(MODELS)}, an ONNX file's path or a callable, got {type(model).__name__}")
        session = _session(path, n)
        scale = side / min(h, w)
        size = (max(mult, round(h * scale / mult) * mult), max(mult, round(w * scale / mult) * mult))
        x = (_resize(coded, size) - _MEAN) / _STD
        feed = {session.get_inputs()[0].name: np.ascontiguousarray(x.transpose(2, 0, 1)[None], dtype=np.float32)}
        out = np.asarray(session.run(None, feed)[0], dtype=np.float32)
        out = out.reshape(out.shape[-2:])
    if not np.all(np.isfinite(out)):
        raise ValueError("the depth network's output holds NaN or inf")
    return out if out.shape == (h, w) else _resize(out, (h, w))


def _ground_rows(camera: Camera) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """The ground pixels used for the fit and the ground plane's inverse depth there."""
    from skyfall.photo import ground_plane_depth

    g = ground_plane_depth(camera).astype(np.float64)
    below = np.isfinite(g).any(axis=1)
    rows = np.flatnonzero(below)
    if rows.size == 0:
        raise ValueError("the horizon lies below the photo: no ground to calibrate the depth against")
    keep = rows[rows >= rows[-1] - max(1, math.ceil(GROUND_SHARE * rows.size)) + 1]
    mask = np.zeros(g.shape, dtype=bool)
    mask[keep] = True
    mask &= np.isfinite(g)
    return mask, 1.0 / np.where(mask, g, 1.0)


def to_metres(
    relative: Any,
    *,
    camera: Camera | None = None,
    distance_m: float | None = None,
    sky_mask: Any = None,
) -> tuple[NDArray[np.float32], float, float]:
    """Turn affine-invariant inverse depth r = s / Z + t into metres (module docstring: the rules).

    Parameters
    ----------
    relative : array_like, shape (H, W)
        The network's output (:func:`relative_inverse_depth`), larger is nearer.
    camera : Camera, optional
        A camera with its resolution above a level ground (``position_m[1]`` its height,
        its pitch setting the horizon): fits s and t on the ground.
    distance_m : float, optional
        The median distance of what is not sky, m, in (0, 1e5].
    sky_mask : array_like of bool, shape (H, W), optional
        Known sky, left out of the median and set to ``inf``.

    Returns
    -------
    depth_m : ndarray of float32, shape (H, W)
        ``inf`` where r - t <= 0 or on the sky mask.
    s, t : float
        The scale and shift found.
    """
    try:
        raw = np.asarray(relative)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"relative must be an (H, W) array of real numbers: {exc}") from None
    if raw.dtype.kind not in "iuf":
        raise TypeError(f"relative must be an (H, W) array of real numbers, got dtype {raw.dtype}")
    r = raw.astype(np.float64)
    if r.ndim != 2 or r.size == 0 or not np.all(np.isfinite(r)):
        raise ValueError(f"relative must be a finite, non-empty (H, W) map, got shape {r.shape}")
    sky = np.zeros(r.shape, bool) if sky_mask is None else np.asarray(sky_mask, dtype=bool)
    if sky.shape != r.shape:
        raise ValueError(f"sky_mask has shape {sky.shape}, relative {r.shape}")
    if camera is None and distance_m is None:
        raise ValueError("give camera (a ground plane: its height and pitch), distance_m, or both: relative depth has no scale of its own")
    rows: list[NDArray[np.float64]] = []
    rhs: list[NDArray[np.float64]] = []
    weights: list[NDArray[np.float64]] = []
    if camera is not None:
        if camera.width != r.shape[1] or camera.height != r.shape[0]:
            camera = camera.with_resolution(r.shape[1], r.shape[0])
        mask, q = _ground_rows(camera)
        mask &= ~sky
        keep = mask.copy()
        for _ in range(3):  # trimmed least squares: r = s q + t on the ground
            a = np.stack([q[keep], np.ones(int(keep.sum()))], axis=1)
            (s, t), *_ = np.linalg.lstsq(a, r[keep], rcond=None)
            res = np.abs(r - (s * q + t))
            mad = float(np.median(res[mask])) + 1e-12
            keep = mask & (res <= 3.0 * mad / 0.6745)
        rows.append(np.stack([q[keep], np.ones(int(keep.sum()))], axis=1))
        rhs.append(r[keep])
        weights.append(np.ones(int(keep.sum())))
    if distance_m is not None:
        d = in_range("distance_m", distance_m)
        # the median over what is not sky: the mask's, and with a ground fit where r > t
        solid = ~sky if camera is None else ~sky & (r > t + 1e-9 * max(abs(t), 1.0))
        rm = float(np.median(r[solid])) if solid.any() else float(np.median(r))
        # median pixel at d: r_med = s / d + t (with t = 0 alone)
        rows.append(np.array([[1.0 / d, 1.0 if camera is not None else 0.0]]))
        rhs.append(np.array([rm]))
        weights.append(np.array([float(max(1, sum(len(x) for x in rhs[:-1])))]))
    a = np.concatenate(rows)
    b = np.concatenate(rhs)
    wt = np.sqrt(np.concatenate(weights))
    if camera is None:  # t = 0: s alone
        s, t = float(b[0] / a[0, 0]), 0.0
    else:
        (s, t), *_ = np.linalg.lstsq(a * wt[:, None], b * wt, rcond=None)
        s, t = float(s), float(t)
    if not s > 0.0:
        why = "does not grow nearer toward the ground; check the camera's height and horizon" if camera is not None else "is not positive outside the sky: nothing in it is nearer than the sky"
        raise ValueError(f"relative: the fit found scale s = {s:.4g} <= 0: the map {why}")
    inv = (r - t) / s
    with np.errstate(divide="ignore"):
        depth = np.where(inv > 0.0, 1.0 / np.where(inv > 0.0, inv, 1.0), np.inf)
    depth[sky] = np.inf
    return depth.astype(np.float32), s, t


def estimate(
    image: Any,
    *,
    model: str | os.PathLike[str] | Callable[[NDArray[np.float32]], Any] = "depth-anything-v2-small",
    camera_height_m: float | None = None,
    horizon_row: float | None = None,
    vertical_fov_deg: float = 60.0,
    distance_m: float | None = None,
    sky_mask: Any = None,
    threads: int = 1,
) -> NDArray[np.float32]:
    """Depth in metres for a photo without it: :func:`relative_inverse_depth`, then
    :func:`to_metres`.

    Parameters
    ----------
    image : array_like, shape (H, W, 3) or (H, W, 4)
        uint8 sRGB codes, or sRGB-encoded floats in [0, 1].
    model : str, path or callable
        As for :func:`relative_inverse_depth`.
    camera_height_m, horizon_row : float, optional
        The ground plane to calibrate on (either asks for it; default height 1.6 m, horizon
        the middle row), as for :class:`skyfall.PhotoScene`.
    vertical_fov_deg : float
        The photo's vertical field of view, degrees (for the ground plane).
    distance_m : float, optional
        The median distance of what is not sky, m. With neither this nor the ground plane,
        the median is put at :data:`skyfall.photo_scene.DEFAULT_DISTANCE_M`.
    sky_mask : array_like of bool, optional
        Known sky (e.g. :func:`skyfall.photo.estimate_sky_mask`).
    threads : int
        onnxruntime's threads (default 1, deterministic).

    Returns
    -------
    ndarray of float32, shape (H, W)
        Metres along the optical axis, ``inf`` for sky: ready for
        ``PhotoScene(image, depth_m)``.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((21, 30, 3), np.uint8)
    >>> near = lambda x: np.linspace(0.5, 2.0, 21)[:, None] * np.ones((1, 30))  # nearer below
    >>> d = estimate(img, model=near, distance_m=4.0)
    >>> round(float(np.median(d)), 3), bool(d[0, 0] > d[-1, 0])
    (4.0, True)
    """
    from skyfall.photo import level_camera
    from skyfall.photo_scene import DEFAULT_DISTANCE_M

    rel = relative_inverse_depth(image, model=model, threads=threads)
    h, w = rel.shape
    cam = None
    if camera_height_m is not None or horizon_row is not None:
        cam = level_camera(w, h, camera_height_m=1.6 if camera_height_m is None else camera_height_m, horizon_row=horizon_row, vertical_fov_deg=vertical_fov_deg)
    dist = distance_m if (distance_m is not None or cam is not None) else DEFAULT_DISTANCE_M
    depth, _, _ = to_metres(rel, camera=cam, distance_m=dist, sky_mask=sky_mask)
    return depth
