"""Image files through OpenImageIO: exact float round trips, sRGB checked against colour-science."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from skyfall import io, rain


def test_rain_atlas_round_trips_bit_exact(tmp_path):
    rates, diams = (1.0, 5.0, 10.0, 20.0), (1.0, 1.2, 1.4, 1.6, 1.8, 2.0)
    tex = rain.textures(rates, diams, size_px=64, seed=5)
    path = tmp_path / "atlas.exr"
    rain.write_atlas(path, tex, rates, diams)
    back, r2, d2 = rain.read_atlas(path)
    assert back.dtype == np.float32 and back.shape == tex.shape
    assert back.tobytes() == tex.tobytes()
    np.testing.assert_array_equal(r2, rates)
    np.testing.assert_array_equal(d2, diams)
    # The mosaic is what an EXR viewer shows: rows are rates, columns diameters.
    mosaic = io.read_image(path)
    np.testing.assert_array_equal(mosaic[64:128, 128:192, 0], tex[1, 2])


def test_exr_keeps_named_float_channels(tmp_path):
    rng = np.random.default_rng(0)
    img = rng.normal(size=(7, 5, 3)).astype(np.float32) * 100
    path = tmp_path / "f.exr"
    io.write_image(path, img, channel_names=["depth_m", "rain_alpha", "transmittance"])
    back, meta = io.read_image_with_metadata(path)
    assert back.tobytes() == img.tobytes()
    assert meta["channel_names"] == ["depth_m", "rain_alpha", "transmittance"]


def test_png_encoding_matches_colour_science(tmp_path):
    lin = np.linspace(0.0, 1.0, 256, dtype=np.float32).reshape(16, 16, 1).repeat(3, axis=2)
    want = np.rint(colour.cctf_encoding(lin.astype(np.float64), function="sRGB") * 255).astype(np.uint8)
    np.testing.assert_array_equal(io.to_srgb8(lin), want)
    np.testing.assert_allclose(io.encode_srgb(lin), colour.cctf_encoding(lin.astype(np.float64), function="sRGB"), atol=2e-6)
    np.testing.assert_allclose(io.decode_srgb(want / 255.0), colour.cctf_decoding(want / 255.0, function="sRGB"), atol=2e-6)
    path = tmp_path / "g.png"
    io.write_image(path, lin)
    back = io.read_image(path)
    # Decoded values sit within half an 8-bit step (in encoded space) of the input.
    enc_err = np.abs(io.encode_srgb(back) - io.encode_srgb(lin))
    assert enc_err.max() <= 0.5 / 255 + 1e-6


def test_png_alpha_is_kept_unassociated(tmp_path):
    img = np.zeros((4, 4, 4), dtype=np.float32)
    img[..., 0] = 0.5
    img[..., 3] = np.linspace(0.0, 1.0, 16).reshape(4, 4)
    path = tmp_path / "a.png"
    io.write_image(path, img)
    back = io.read_image(path)
    np.testing.assert_allclose(back[..., 3], img[..., 3], atol=0.5 / 255)
    # colour where alpha > 0 is not un-premultiplied by OIIO
    visible = img[..., 3] > 0
    np.testing.assert_allclose(back[..., 0][visible], 0.5, atol=0.01)


def test_errors_are_clear(tmp_path):
    with pytest.raises(OSError, match="cannot read"):
        io.read_image(tmp_path / "missing.exr")
    with pytest.raises(OSError, match="cannot write"):
        io.write_image(tmp_path / "no_such_dir" / "x.exr", np.zeros((2, 2), np.float32))
    with pytest.raises(ValueError, match="shape"):
        io.write_image(tmp_path / "x.exr", np.zeros((2, 2, 2, 2), np.float32))
    with pytest.raises(ValueError, match="channel_names"):
        io.write_image(tmp_path / "x.exr", np.zeros((2, 2, 3), np.float32), channel_names=["a"])
    with pytest.raises(TypeError, match="dtype"):
        io.write_image(tmp_path / "x.exr", np.array([["a"]]))
    io.write_image(tmp_path / "plain.exr", np.zeros((2, 2), np.float32))
    with pytest.raises(ValueError, match="not a skyfall rain atlas"):
        rain.read_atlas(tmp_path / "plain.exr")


def test_16_bit_files_keep_their_16_bits(tmp_path):
    # read_stored gives a file's own codes; read_image decodes 16-bit codes from all 16 bits
    # (it used to read them as 8-bit), against colour-science's sRGB decoding.
    import colour

    from skyfall import io as sio

    codes = (np.arange(4 * 6 * 3, dtype=np.uint32).reshape(4, 6, 3) * 911 % 65536).astype(np.uint16)
    path = tmp_path / "d.png"
    sio.write_image(path, codes)
    stored, meta = sio.read_stored(path)
    assert stored.dtype == np.uint16 and meta["alpha_channel"] == -1
    np.testing.assert_array_equal(stored, codes)
    want = colour.cctf_decoding(codes / 65535.0, function="sRGB")
    np.testing.assert_allclose(sio.read_image(path), want, atol=2e-6)
    eight = (codes >> 8).astype(np.uint8)
    sio.write_image(tmp_path / "e.png", eight)
    assert sio.read_stored(tmp_path / "e.png")[0].dtype == np.uint8
