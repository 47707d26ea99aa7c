"""Clips as video files: temporally coherent rain (:meth:`skyfall.Renderer.render_sequence_srgb8`)
written as H.264 MP4 through PyAV (FFmpeg), for video deraining datasets and for looking at.

The rain is anchored in the world, so consecutive frames of a sequence show the same drops
falling; a clip's frames go to the encoder one at a time as they are rendered (one frame's
memory however long the clip). ``lossless=True`` keeps every RGB byte (x264's RGB mode at
constant quality 0: decode it back with :func:`read_video` and the frames are the ones
rendered); the default is x264 in 4:2:0 YUV at ``crf`` 18, visually transparent and about
ten times smaller. The RGB to YUV conversion (BT.709, limited range, each 2 x 2 block's chroma
averaged) is skyfall's own, in numpy (FFmpeg's converter, swscale, gave a few codes'
difference between runs on a loaded machine), and the encoder runs on one thread. Lossless
clips are then the same bytes in any process. Lossy ones are not always: the same YUV frames
(hashed equal) gave 2 to 6 different x264 byte streams in 16 processes here, with or without
x264's ``psy`` and with explicit timestamps; valgrind's memcheck found no read of unset memory,
and the cause is not known. Every variant decoded to the frames at 37.7 to 39.1 dB PSNR
(a 32 x 24 street clip).
Needs PyAV (``pip install skyfall[video]``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from fractions import Fraction
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import flag, integer, real

__all__ = ["read_video", "write_video"]


def _av() -> Any:
    try:
        import av
    except ImportError as exc:  # pragma: no cover - av is a declared extra and a dev requirement
        raise ImportError("skyfall.video needs PyAV: pip install 'skyfall[video]' (or pip install av)") from exc
    return av


def _frame(i: int, frame: Any) -> NDArray[np.uint8]:
    a = np.asarray(frame)
    if a.dtype != np.uint8:
        raise TypeError(f"frames[{i}] must be uint8 sRGB (e.g. Renderer.render_srgb8's), got dtype {a.dtype}")
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=2)  # a mask or a layer, as grey
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"frames[{i}] must have shape (H, W, 3) or (H, W), got {a.shape}")
    return np.ascontiguousarray(a)


# BT.709 luma weights; FFmpeg's codes for BT.709 (colorspace, primaries, transfer) and for the
# limited ("MPEG") range, written into the stream so decoders convert back with the same matrix.
_KR, _KB = 0.2126, 0.0722
_BT709, _LIMITED = 1, 1


def _yuv420(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """An even-sized sRGB frame as one yuv420p array (Y, then U, then V: (1.5 H, W)), BT.709
    limited range, the chroma of each 2 x 2 block averaged (deterministic, unlike a threaded
    converter)."""
    c = rgb.astype(np.float32) * np.float32(1.0 / 255.0)
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    y = _KR * r + (1.0 - _KR - _KB) * g + _KB * b
    cb = (b - y) / (2.0 * (1.0 - _KB))
    cr = (r - y) / (2.0 * (1.0 - _KR))
    h, w = y.shape

    def half(p: NDArray[np.float32]) -> NDArray[np.float32]:
        return np.asarray(p.reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3)), dtype=np.float32)

    def code(v: NDArray[np.float32], scale: float, offset: float) -> NDArray[np.uint8]:
        return np.asarray(np.clip(np.rint(offset + scale * v), 0, 255), dtype=np.uint8)

    u, v = code(half(cb), 224.0, 128.0), code(half(cr), 224.0, 128.0)
    return np.concatenate([code(y, 219.0, 16.0), u.reshape(h // 4, w), v.reshape(h // 4, w)], axis=0)


def write_video(
    path: str | PathLike[str],
    frames: Iterable[Any],
    *,
    fps: float = 30.0,
    lossless: bool = False,
    crf: int = 18,
) -> int:
    """Encode 8-bit sRGB frames into an H.264 video file (MP4 by its extension).

    Parameters
    ----------
    path : str or path-like
        The file; written under a temporary name beside it and renamed when complete, so a
        killed run never leaves a half-written file under ``path``.
    frames : iterable of ndarray of uint8, shape (H, W, 3) or (H, W)
        The frames, all of one size, consumed one at a time (a generator such as
        :meth:`skyfall.Renderer.render_sequence_srgb8` keeps one in memory). (H, W) frames
        (a mask, a layer scaled to bytes) are written grey.
    fps : float
        Frames per second, in (0, 1000].
    lossless : bool
        Keep every byte: x264's RGB mode at quality 0. Otherwise 4:2:0 YUV at ``crf``, which
        needs an even width and height.
    crf : int
        x264's constant rate factor for lossy video, in [0, 51] (lower is better; 18 is
        visually transparent).

    Returns
    -------
    int
        The number of frames written.

    Raises
    ------
    ValueError
        No frames, frames of different sizes, an odd size for lossy video, or a parameter
        outside its range.
    TypeError
        A frame that is not uint8.
    """
    av = _av()
    rate = real("fps", fps)
    if not 0.0 < rate <= 1000.0:
        raise ValueError(f"fps = {fps} is outside the valid range (0, 1000]")
    exact = flag("lossless", lossless)
    quality = integer("crf", crf, 0, 51)
    target = Path(path)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.part{target.suffix}")
    count = 0
    shape: tuple[int, ...] | None = None
    try:
        with av.open(str(tmp), mode="w") as container:
            stream: Any = None
            for i, raw in enumerate(frames):
                frame = _frame(i, raw)
                if shape is None:
                    shape = frame.shape
                    h, w = shape[0], shape[1]
                    if not exact and (h % 2 or w % 2):
                        raise ValueError(f"frames are {w}x{h} px: lossy H.264 (4:2:0) needs an even width and height; crop a pixel or pass lossless=True")
                    stream = container.add_stream("libx264rgb" if exact else "libx264", rate=Fraction(rate).limit_denominator(1001))
                    stream.width, stream.height = w, h
                    stream.pix_fmt = "rgb24" if exact else "yuv420p"
                    stream.thread_count = 1  # the same frames give the same bytes
                    stream.options = {"crf": str(0 if exact else quality), "preset": "medium"}
                    if not exact:
                        ctx = stream.codec_context
                        ctx.colorspace, ctx.color_range = _BT709, _LIMITED
                        ctx.color_primaries, ctx.color_trc = _BT709, _BT709
                elif frame.shape != shape:
                    raise ValueError(f"frames[{i}] has shape {frame.shape}, the first frame {shape}: a video's frames share one size")
                if exact:
                    picture = av.VideoFrame.from_ndarray(frame, format="rgb24")
                else:
                    picture = av.VideoFrame.from_ndarray(_yuv420(frame), format="yuv420p")
                    picture.colorspace, picture.color_range = _BT709, _LIMITED
                for packet in stream.encode(picture):
                    container.mux(packet)
                count += 1
            if stream is None:
                raise ValueError("frames is empty: a video needs at least one frame")
            for packet in stream.encode():
                container.mux(packet)
        tmp.replace(target)
    finally:
        tmp.unlink(missing_ok=True)
    return count


def read_video(path: str | PathLike[str]) -> Iterator[NDArray[np.uint8]]:
    """The frames of a video file as uint8 sRGB (H, W, 3) arrays, decoded one at a time.

    Parameters
    ----------
    path : str or path-like
        A video FFmpeg reads (e.g. one :func:`write_video` wrote).

    Returns
    -------
    iterator of ndarray of uint8, shape (H, W, 3)

    Raises
    ------
    FileNotFoundError, PermissionError, IsADirectoryError
        When ``path`` cannot be opened.
    ValueError
        When it is not a video FFmpeg can decode (naming the file), or has no video stream.
    """
    av = _av()
    name = os.fspath(path)

    def refuse(e: Exception) -> ValueError:
        return ValueError(f"{name!r} is not a video FFmpeg can decode (an .mp4 such as write_video writes): {e}")

    try:
        container = av.open(str(name))
    except (FileNotFoundError, PermissionError, IsADirectoryError):
        raise
    except (av.error.FFmpegError, OSError, ValueError) as e:
        raise refuse(e) from None
    with container:
        if not container.streams.video:
            raise ValueError(f"{name!r} has no video stream")
        frames = container.decode(video=0)
        while True:
            try:
                frame = next(frames)
            except StopIteration:
                return
            except (FileNotFoundError, PermissionError, IsADirectoryError):
                raise
            except (av.error.FFmpegError, OSError, ValueError) as e:
                raise refuse(e) from None
            yield np.asarray(frame.to_ndarray(format="rgb24"), dtype=np.uint8)
