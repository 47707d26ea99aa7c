"""scenes.py's public functions: every parameter of the wrong type is a TypeError naming it,
every value out of range a ValueError naming it, its value and what is valid."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, PointLight, SpotLight, scenes

BOX = {"min": (0, 0, -10), "max": (2, 3, -8)}
IMG = np.zeros((4, 6, 3), np.float32)
DEPTH = np.full((4, 6), 10.0, np.float32)


@pytest.mark.parametrize("name", ["lamps", "headlights", "awning"])
@pytest.mark.parametrize("value", ["no", "False", 0, 1, None, 1.0])
def test_street_switches_take_booleans_only(name, value):
    # street(lamps='no') used to light the lamps: any truthy object turned a switch on
    with pytest.raises(TypeError, match=rf"{name} must be True or False, got {type(value).__name__}"):
        scenes.street(**{name: value})


def test_street_switches_take_numpy_booleans():
    on = scenes.street(lamps=np.bool_(True), headlights=np.bool_(True), awning=np.bool_(False))
    off = scenes.street(lamps=False, headlights=False, awning=True)
    assert len(on.lights) == 18 and len(off.lights) == 0
    assert len(on.boxes) == len(off.boxes) - 1  # no awning


@pytest.mark.parametrize("name", ["length_m", "width_m"])
@pytest.mark.parametrize("value", ["10", b"10", True, None, [10.0]])
def test_street_sizes_are_real_numbers(name, value):
    # street(width_m='10') used to fail with a bare "unsupported operand type(s) for /"
    with pytest.raises(TypeError, match=rf"{name} must be a real number, got {type(value).__name__}"):
        scenes.street(**{name: value})


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("length_m", 10.0, r"length_m = 10.0 is outside the valid range \[20, 1000\] m"),
        ("length_m", float("nan"), r"length_m = nan is outside the valid range \[20, 1000\] m"),
        ("width_m", 200, r"width_m = 200.0 is outside the valid range \[4, 100\] m"),
        ("seed", -1, r"seed = -1 is outside the valid range \[0, 18446744073709551615\]"),
    ],
)
def test_street_values_out_of_range(name, value, message):
    with pytest.raises(ValueError, match=message):
        scenes.street(**{name: value})


@pytest.mark.parametrize("value", [1.5, "0", True, None])
def test_street_seed_is_an_int(value):
    with pytest.raises(TypeError, match=rf"seed must be an int, got {type(value).__name__}"):
        scenes.street(seed=value)


def test_street_sizes_and_seeds_of_numpy_types_work():
    a = scenes.street(width_m=np.float32(10.0), length_m=np.int64(60), seed=np.uint64(3))
    b = scenes.street(width_m=10.0, length_m=60.0, seed=3)
    np.testing.assert_array_equal(a.boxes, b.boxes)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"ground": "no"}, TypeError, r"ground must be True or False, got str 'no'"),
        ({"ground_albedo": "grey"}, TypeError, r"ground_albedo must be a real number"),
        ({"ground_albedo": 1.5}, ValueError, r"ground_albedo = 1.5 must be one or three numbers in \[0, 1\]"),
        ({"ground_albedo": (0.1, 0.2)}, ValueError, r"ground_albedo = \(0.1, 0.2\) must be one or three"),
        ({"camera": "front"}, TypeError, r"camera must be a skyfall.Camera or None, got str"),
        ({"lamps_m": "abc"}, TypeError, r"lamps_m must be a real number"),
        ({"lamps_m": [1.0, 2.0]}, ValueError, r"lamps_m must have shape \(L, 3\), got shape \(2,\)"),
        ({"lamps_m": [[0, 5, -8], [0, 5, np.nan]]}, ValueError, r"lamps_m\[1, 2\] = nan is outside the valid range \[-1e7, 1e7\] m"),
        ({"lights": "abc"}, TypeError, r"lights must be a sequence of PointLight or SpotLight, got str"),
        ({"lights": PointLight((0, 5, -8), 100.0)}, TypeError, r"lights must be a sequence of lights, got one PointLight: pass \(light,\)"),
        ({"lights": (PointLight((0, 5, -8), 100.0), "lamp")}, TypeError, r"lights\[1\] must be a PointLight or SpotLight, got str"),
    ],
)
def test_boxes_parameters_are_named(kwargs, error, message):
    with pytest.raises(error, match=message):
        scenes.boxes([BOX], **kwargs)


@pytest.mark.parametrize(
    ("box_list", "error", "message"),
    [
        ("boxes", TypeError, r"boxes must be a sequence of dicts, got str"),
        (BOX, TypeError, r"boxes must be a sequence of dicts, got dict"),
        ([((0, 0, 0), (1, 1, 1))], TypeError, r"boxes\[0\] must be a dict with 'min' and 'max' corners, got tuple"),
        ([{"min": (0, 0, 0)}], ValueError, r"boxes\[0\] must be a dict with 'min' and 'max' corners"),
        ([BOX, {**BOX, "albdo": 0.5}], ValueError, r"boxes\[1\] has unknown keys \['albdo'\]: a box takes \['min', 'max', 'albedo'\]"),
        ([{"min": "abc", "max": (1, 1, 1)}], TypeError, r"boxes\[0\].min must be a real number"),
        ([{"min": (0, 0, 0), "max": (1, 1, None)}], TypeError, r"boxes\[0\].max must be a real number"),
        ([{"min": (0, 0), "max": (1, 1, 1)}], ValueError, r"boxes\[0\]: min and max must be 3 finite numbers \(m\), got min \(0, 0\)"),
        ([{**BOX, "albedo": "red"}], TypeError, r"boxes\[0\].albedo must be a real number"),
        ([{**BOX, "albedo": -0.1}], ValueError, r"boxes\[0\].albedo = -0.1 must be one or three numbers in \[0, 1\]"),
    ],
)
def test_box_lists_are_named_by_entry(box_list, error, message):
    with pytest.raises(error, match=message):
        scenes.boxes(box_list)


def test_good_boxes_keep_what_was_given():
    light = SpotLight((0.0, 0.7, -12.0), (0.0, 0.0, 1.0), 1000.0)
    cam = Camera((0.0, 1.6, 0.0))
    scene = scenes.boxes([{**BOX, "albedo": 0.3}], ground=np.bool_(False), ground_albedo=0.2, camera=cam, lamps_m=[[0, 5, -8]], lights=[light])
    assert scene.ground is False and scene.camera is cam and scene.lights == (light,)
    np.testing.assert_array_equal(scene.boxes, np.array([[0, 0, -10, 2, 3, -8, 0.3, 0.3, 0.3]], np.float32))
    assert scene.ground_albedo == (0.2, 0.2, 0.2) and scene.lamps_m.tolist() == [[0.0, 5.0, -8.0]]
    assert scenes.boxes([], lamps_m=[]).lamps_m.shape == (0, 3)


def test_empty_passes_its_parameters_on_and_names_them():
    assert scenes.empty(ground_albedo=0.5).ground_albedo == (0.5, 0.5, 0.5)
    with pytest.raises(TypeError, match="ground_albedo"):
        scenes.empty(ground_albedo="x")
    with pytest.raises(TypeError, match="camera must be a skyfall.Camera"):
        scenes.empty(camera=(0, 1.6, 0))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("args", "kwargs", "error", "message"),
    [
        (("photo.png", DEPTH), {}, TypeError, r"image must be an array, got the str 'photo.png'; for a file: read it with skyfall.io.read_image"),
        ((Path("photo.png"), DEPTH), {}, TypeError, r"image must be an array, got the \w*Path 'photo.png'"),
        ((IMG, "depth.exr"), {}, TypeError, r"depth_m must be an array, got the str 'depth.exr'; for a file: read it with skyfall.io.read_depth"),
        ((IMG.astype(bool), DEPTH), {}, TypeError, r"image must be uint8 \(sRGB codes\) or float, got dtype bool"),
        ((IMG.astype(np.uint16), DEPTH), {}, TypeError, r"image must be uint8 \(sRGB codes\) or float, got dtype uint16"),
        ((IMG[..., 0], DEPTH), {}, ValueError, r"image must have shape \(H, W, 3\), got \(4, 6\)"),
        ((IMG, DEPTH.astype(bool)), {}, TypeError, r"depth_m must be numeric, got dtype bool"),
        ((IMG, DEPTH[:, :5]), {}, ValueError, r"depth_m has shape \(4, 5\), the image is \(4, 6\)"),
        ((IMG, DEPTH), {"camera": "cam"}, TypeError, r"camera must be a skyfall.Camera or None, got str"),
        ((IMG, DEPTH), {"vertical_fov_deg": "60"}, TypeError, r"vertical_fov_deg must be a real number, got str"),
        ((IMG, DEPTH), {"camera": Camera(), "vertical_fov_deg": "60"}, TypeError, r"vertical_fov_deg must be a real number"),
        ((IMG, DEPTH), {"vertical_fov_deg": 180.0}, ValueError, r"vertical_fov_deg = 180.0 is outside the valid range"),
        ((IMG, DEPTH), {"lights": "ab"}, TypeError, r"lights must be a sequence of PointLight or SpotLight, got str"),
        ((IMG, DEPTH), {"lights": [None]}, TypeError, r"lights\[0\] must be a PointLight or SpotLight, got NoneType"),
        ((IMG, DEPTH), {"occluders": BOX}, TypeError, r"occluders must be a sequence of dicts, got dict"),
        ((IMG, DEPTH), {"occluders": [{"min": (0, 0, "a"), "max": (1, 1, 1)}]}, TypeError, r"occluders\[0\].min must be a real number"),
        ((IMG, DEPTH), {"occluders": [{"min": (0, 0, 0), "max": (1, 1, 1), "albedo": 0.5, "hight": 2}]}, ValueError, r"occluders\[0\] has unknown keys \['hight'\]"),
    ],
)
def test_photo_scene_parameters_are_named(args, kwargs, error, message):
    # (a float image says it is linear, so the case's own parameter is the one refused)
    if isinstance(args[0], np.ndarray) and args[0].dtype.kind == "f":
        kwargs = {"encoding": "linear", **kwargs}
    with pytest.raises(error, match=message):
        PhotoScene(*args, **kwargs)


@pytest.mark.parametrize(
    ("name", "bad", "message"),
    [
        ("image", np.nan, r"image\[1, 2, 0\] = nan is outside the valid range \[0, inf\) \(linear RGB\)"),
        ("image", np.inf, r"image\[1, 2, 0\] = inf is outside the valid range \[0, inf\)"),
        ("image", -0.5, r"image\[1, 2, 0\] = -0.5 is outside the valid range \[0, inf\)"),
        # NaN depth is no data, filled (tests/test_depth_formats.py), not refused
        ("depth_m", -2.0, r"depth_m\[1, 2\] = -2.0 is outside the valid range \[0, inf\] m"),
    ],
)
def test_photo_values_out_of_range_name_the_first_pixel(name, bad, message):
    img, depth = IMG.copy(), DEPTH.copy()
    (img[1, 2, 0:1] if name == "image" else depth[1, 2:3])[...] = bad
    with pytest.raises(ValueError, match=message):
        PhotoScene(img, depth, encoding="linear")


def test_photo_scene_takes_sky_and_its_own_camera():
    depth = DEPTH.copy()
    depth[0] = np.inf  # sky
    cam = Camera((0.0, 1.6, 0.0), vertical_fov_deg=40.0)
    photo = PhotoScene(IMG, depth, camera=cam, lights=[PointLight((0, 5, -8), 100.0)], encoding="linear")
    assert photo.shape == (4, 6) and photo.camera.vertical_fov_deg == 40.0 and len(photo.lights) == 1
    assert np.isinf(photo.depth_m[0]).all()
