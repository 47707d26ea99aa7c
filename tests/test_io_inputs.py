"""Image I/O never misreads its input silently: integer arrays are codes only when they are
uint8 (uint16 into PNG), data layers can be written linear, NaN has no 8-bit code, and codes
outside [0, 255] do not wrap. Files are read back with OpenImageIO directly, as stored."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from skyfall import io


def _raw(path: Path, fmt: str) -> np.ndarray:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    try:
        spec = inp.spec()
        return np.asarray(inp.read_image(fmt)).reshape(spec.height, spec.width, spec.nchannels)
    finally:
        inp.close()


def test_integer_arrays_are_codes_or_refused(tmp_path: Path) -> None:
    # int64 128 and uint16 30000 were written as 255 (taken for linear light and clipped).
    with pytest.raises(TypeError, match="int64"):
        io.write_image(tmp_path / "a.png", np.full((2, 3), 128, np.int64))
    with pytest.raises(TypeError, match="uint16"):
        io.write_image(tmp_path / "a.jpg", np.full((2, 3), 30000, np.uint16))
    codes = np.array([[0, 30000, 65535]], np.uint16)
    io.write_image(tmp_path / "d.png", codes)
    np.testing.assert_array_equal(_raw(tmp_path / "d.png", "uint16")[..., 0], codes)
    bytes8 = np.array([[0, 7, 128, 255]], np.uint8)
    io.write_image(tmp_path / "b.png", bytes8)
    np.testing.assert_array_equal(_raw(tmp_path / "b.png", "uint8")[..., 0], bytes8)


def test_data_layers_can_be_written_linear(tmp_path: Path) -> None:
    alpha = np.array([[0.0, 0.214, 0.5, 1.0, 2.0]], np.float32)
    io.write_image(tmp_path / "alpha.png", alpha, encoding="linear")
    np.testing.assert_array_equal(_raw(tmp_path / "alpha.png", "uint8")[..., 0], [[0, 55, 128, 255, 255]])
    io.write_image(tmp_path / "view.png", alpha)  # the default encodes for viewing
    np.testing.assert_array_equal(_raw(tmp_path / "view.png", "uint8")[..., 0], [[0, 127, 188, 255, 255]])
    with pytest.raises(ValueError, match="encoding"):
        io.write_image(tmp_path / "x.png", alpha, encoding="gamma")


def test_nan_has_no_8_bit_code(tmp_path: Path) -> None:
    img = np.array([[0.5, np.nan, np.nan]], np.float32)
    with pytest.raises(ValueError, match="2 NaN"):
        io.write_image(tmp_path / "n.png", img)
    io.write_image(tmp_path / "n.exr", img)  # float files keep it
    assert np.isnan(_raw(tmp_path / "n.exr", "float")[0, 1, 0])


def test_codes_outside_a_byte_do_not_wrap() -> None:
    with pytest.raises(ValueError, match="256"):
        io.decode_srgb8([256, -1, 1000])  # decoded as 0, 255, 232 before
    with pytest.raises(ValueError, match="1.5"):
        io.decode_srgb8(np.array([1.5]))
    with pytest.raises(TypeError):
        io.decode_srgb8(np.array(["a"]))
    np.testing.assert_array_equal(io.decode_srgb8(np.array([0, 128, 255], np.int64)), io.decode_srgb8(np.array([0, 128, 255], np.uint8)))


def test_integer_depth_maps_state_their_unit() -> None:
    # uint16 millimetres read as metres put a wall 2.5 m away at 2.5 km: fully fogged.
    from skyfall import PhotoScene, Renderer, Weather

    mm = np.full((12, 16), 2500, np.uint16)
    img = np.full((12, 16, 3), 0.3, np.float32)
    with pytest.raises(TypeError, match="depth_scale_m"):
        PhotoScene(img, mm, encoding="linear")
    photo = PhotoScene(img, mm, depth_scale_m=0.001, encoding="linear")
    np.testing.assert_allclose(photo.depth_m, 2.5)
    fog = Weather(visibility_m=1000.0)
    t = Renderer(16, 12, backend="cpu").render(photo, fog).layers["transmittance"]
    assert t.min() > 0.98  # 2.5 m of 1 km visibility (2.5 km would leave about 1e-4)
    for bad in (0.0, -1.0, float("inf"), float("nan")):
        with pytest.raises(ValueError, match="depth_scale_m"):
            PhotoScene(img, mm, depth_scale_m=bad, encoding="linear")
    # a float map is metres: a scale with it is refused by name (it once turned metres into mm)
    np.testing.assert_allclose(PhotoScene(img, np.full((12, 16), 2.5, np.float32), encoding="linear").depth_m, 2.5)
    with pytest.raises(ValueError, match="depth_scale_m applies to integer depth only"):
        PhotoScene(img, np.full((12, 16), 250.0), depth_scale_m=0.01, encoding="linear")
    # a sensor's 0 is no reading: filled from its neighbours, not put at the lens
    holes = mm.copy()
    holes[5, 5] = 0
    np.testing.assert_allclose(PhotoScene(img, holes, depth_scale_m=0.001, encoding="linear").depth_m, 2.5)


def test_float_photos_state_their_encoding() -> None:
    # scikit-image's img_as_float gives sRGB-encoded floats; read as linear, a mean code of 65
    # came out as 133 in clear weather.
    from skyfall import PhotoScene, Renderer, Weather

    codes = np.full((6, 8, 3), 65, np.uint8)
    as_float = codes.astype(np.float32) / 255.0  # what img_as_float returns
    with pytest.raises(ValueError, match="encoding"):
        PhotoScene(as_float, np.full((6, 8), np.inf, np.float32))
    photo = PhotoScene(as_float, np.full((6, 8), np.inf, np.float32), encoding="srgb")
    out = Renderer(8, 6, backend="cpu").render_srgb8(photo, Weather())
    assert np.all(out == 65)  # clear weather gives the photo back
    np.testing.assert_allclose(photo.image, io.decode_srgb8(codes), atol=1e-6)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        PhotoScene(as_float * 5.0, np.full((6, 8), np.inf, np.float32), encoding="srgb")
    with pytest.raises(ValueError, match="uint8"):
        PhotoScene(codes, np.full((6, 8), np.inf, np.float32), encoding="linear")
    assert PhotoScene(codes, np.full((6, 8), np.inf, np.float32), encoding="srgb").srgb8 is not None
