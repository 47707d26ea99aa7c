"""Clips as video (skyfall.video): a rendered rain sequence through PyAV, back again."""

from __future__ import annotations

import numpy as np
import pytest

from skyfall import Renderer, Weather, scenes
from skyfall.video import read_video, write_video

W, H = 64, 48


@pytest.fixture(scope="module")
def clip() -> list[np.ndarray]:
    r = Renderer(W, H, backend="cpu")
    return list(r.render_sequence_srgb8(scenes.street(), Weather(rain_rate_mm_h=30.0), n_frames=6, fps=30.0, seed=2))


def test_lossless_video_gives_every_byte_back(clip, tmp_path):
    path = tmp_path / "rain.mp4"
    assert write_video(path, iter(clip), fps=30.0, lossless=True) == len(clip)
    back = list(read_video(path))
    assert len(back) == len(clip)
    for a, b in zip(back, clip):
        np.testing.assert_array_equal(a, b)
    # consecutive frames differ (the rain falls), and the same frames give the same file
    assert any((a != b).any() for a, b in zip(clip, clip[1:]))
    again = tmp_path / "again.mp4"
    write_video(again, clip, fps=30.0, lossless=True)
    assert again.read_bytes() == path.read_bytes()
    assert not list(tmp_path.glob(".*part*"))  # nothing half-written left behind


def test_lossy_video_is_close_and_keeps_its_rate(clip, tmp_path):
    import av

    path = tmp_path / "rain.mp4"
    write_video(path, clip, fps=24.0, crf=18)
    with av.open(str(path)) as c:
        s = c.streams.video[0]
        assert (s.width, s.height, float(s.average_rate)) == (W, H, 24.0)
    back = np.stack(list(read_video(path))).astype(float)
    mse = np.mean((back - np.stack(clip)) ** 2)
    assert 10 * np.log10(255.0**2 / mse) > 35.0  # PSNR, dB


def test_bad_frames_are_named(tmp_path):
    with pytest.raises(ValueError, match="at least one frame"):
        write_video(tmp_path / "a.mp4", [])
    with pytest.raises(TypeError, match=r"frames\[0\] must be uint8"):
        write_video(tmp_path / "a.mp4", [np.zeros((4, 4, 3), np.float32)])
    with pytest.raises(ValueError, match="even width and height"):
        write_video(tmp_path / "a.mp4", [np.zeros((5, 4, 3), np.uint8)])
    with pytest.raises(ValueError, match=r"frames\[1\] has shape"):
        write_video(tmp_path / "a.mp4", [np.zeros((4, 4, 3), np.uint8), np.zeros((6, 4, 3), np.uint8)])
    with pytest.raises(ValueError, match="fps"):
        write_video(tmp_path / "a.mp4", [np.zeros((4, 4, 3), np.uint8)], fps=0.0)
    assert not (tmp_path / "a.mp4").exists() and not list(tmp_path.glob(".*part*"))
    # a mask (H, W) is written grey
    mask = (np.arange(16 * 16).reshape(16, 16) % 256).astype(np.uint8)
    write_video(tmp_path / "m.mp4", [mask], lossless=True)
    np.testing.assert_array_equal(next(read_video(tmp_path / "m.mp4")), np.repeat(mask[..., None], 3, axis=2))


def test_lossy_video_gives_x264_the_same_yuv_every_time_and_its_yuv_is_bt709(clip, tmp_path):
    import colour

    from skyfall.video import _yuv420

    # x264's bytes can differ between writes (see skyfall.video); what it is given cannot, and
    # every write decodes to the clip
    assert all(_yuv420(f).tobytes() == _yuv420(f.copy()).tobytes() for f in clip)
    for name in ("a.mp4", "b.mp4"):
        write_video(tmp_path / name, clip, fps=30.0)
        back = np.array(list(read_video(tmp_path / name)), np.float64)
        psnr = 10.0 * np.log10(255.0**2 / np.mean((back - np.asarray(clip, np.float64)) ** 2))
        assert psnr > 30.0, (name, psnr)
    # The RGB to YUV conversion against colour-science's BT.709, limited range, 8 bits (luma
    # per pixel; chroma per 2 x 2 block from the block's mean Cb, Cr).
    frame = clip[0]
    # (colour's float output is the code over 255)
    ycbcr = 255 * colour.RGB_to_YCbCr(frame / 255.0, K=colour.WEIGHTS_YCBCR["ITU-R BT.709"], out_bits=8, out_legal=True, out_int=False)
    yuv = _yuv420(frame).astype(float)
    np.testing.assert_allclose(yuv[:H], ycbcr[..., 0], atol=0.51)
    cb = ycbcr[..., 1].reshape(H // 2, 2, W // 2, 2).mean(axis=(1, 3))
    np.testing.assert_allclose(yuv[H : H + H // 4].reshape(H // 2, W // 2), cb, atol=0.51)
