"""skyfall.io.read_depth against hand-written files of each format, with values worked out here
from each format's published rule; a photo's depth holes and its EXIF field of view."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from skyfall import PhotoScene, io
from skyfall.depth_io import read_pfm
from skyfall.photo import exif_vertical_fov_deg, fill_depth_holes


def write_u16(path: Path, codes: np.ndarray) -> None:
    io.write_image(path, codes.astype(np.uint16)[..., None])
    back, _ = io.read_stored(path)
    assert back.dtype == np.uint16 and (back[..., 0] == codes).all()  # the file holds these codes


def test_kitti_is_metres_times_256_with_0_for_no_data(tmp_path):
    codes = np.array([[0, 256, 1280], [65535, 384, 0]], np.uint16)
    write_u16(tmp_path / "k.png", codes)
    d = io.read_depth(tmp_path / "k.png", "kitti")
    want = np.array([[np.nan, 1.0, 5.0], [255.99609375, 1.5, np.nan]], np.float32)
    np.testing.assert_array_equal(d, want)
    assert d.dtype == np.float32


def test_cityscapes_is_disparity_over_baseline_and_fx(tmp_path):
    # (p - 1) / 256 px of disparity: p = 257 is 1 px, 25601 is 100 px, 1 is 0 px (infinitely far)
    codes = np.array([[0, 1, 257, 25601]], np.uint16)
    write_u16(tmp_path / "c.png", codes)
    cam = tmp_path / "c.json"
    cam.write_text(json.dumps({"extrinsic": {"baseline": 0.209313}, "intrinsic": {"fx": 2262.52, "fy": 2265.3017905988554}}))
    d = io.read_depth(tmp_path / "c.png", "cityscapes", camera_json=cam)
    bf = 0.209313 * 2262.52
    np.testing.assert_allclose(d, np.array([[np.nan, np.inf, bf / 1.0, bf / 100.0]], np.float32), rtol=1e-6)
    with pytest.raises(ValueError, match="camera_json"):
        io.read_depth(tmp_path / "c.png", "cityscapes")
    cam.write_text("{}")
    with pytest.raises(ValueError, match="baseline"):
        io.read_depth(tmp_path / "c.png", "cityscapes", camera_json=cam)


def write_pfm(path: Path, rows_top_first: np.ndarray, little: bool = True) -> None:
    """A one-channel PFM by its specification: header, then rows bottom to top."""
    h, w = rows_top_first.shape
    fmt = "<" if little else ">"
    body = b"".join(struct.pack(f"{fmt}{w}f", *row) for row in rows_top_first[::-1])
    path.write_bytes(f"Pf\n{w} {h}\n{-1.0 if little else 1.0}\n".encode() + body)


@pytest.mark.parametrize("little", [True, False])
def test_middlebury_is_baseline_f_over_disparity_plus_doffs(tmp_path, little):
    disp = np.array([[10.0, 20.0, np.inf], [0.0, 100.0, 50.5]], np.float32)
    write_pfm(tmp_path / "disp0.pfm", disp, little)
    (tmp_path / "calib.txt").write_text(
        "cam0=[3979.911 0 1244.772; 0 3979.911 1019.507; 0 0 1]\ncam1=[3979.911 0 1369.115; 0 3979.911 1019.507; 0 0 1]\n"
        "doffs=124.343\nbaseline=193.001\nwidth=2964\nheight=1988\n"
    )
    d = io.read_depth(tmp_path / "disp0.pfm")  # .pfm: Middlebury, calib.txt beside it
    z = lambda px: 193.001 * 3979.911 / (px + 124.343) / 1000.0  # noqa: E731 - the published rule, in m
    want = np.array([[z(10), z(20), np.nan], [z(0), z(100), z(50.5)]], np.float32)
    np.testing.assert_allclose(d, want, rtol=1e-6)
    (tmp_path / "calib.txt").unlink()
    with pytest.raises(FileNotFoundError, match="calib"):
        io.read_depth(tmp_path / "disp0.pfm")
    (tmp_path / "bad.pfm").write_bytes(b"PF\n1 1\n-1\n" + b"\0" * 12)
    with pytest.raises(ValueError, match="3-channel"):
        read_pfm(tmp_path / "bad.pfm")
    (tmp_path / "short.pfm").write_bytes(b"Pf\n4 4\n-1\n" + b"\0" * 12)
    with pytest.raises(ValueError, match="bytes"):
        read_pfm(tmp_path / "short.pfm")


def test_exr_npy_and_scaled_depth(tmp_path):
    m = np.array([[1.5, np.inf], [20.0, 0.25]], np.float32)
    io.write_image(tmp_path / "d.exr", np.stack([m, np.zeros_like(m)], axis=-1), channel_names=["Z", "other"])
    np.testing.assert_array_equal(io.read_depth(tmp_path / "d.exr"), m)
    np.save(tmp_path / "f.npy", m)
    np.testing.assert_array_equal(io.read_depth(tmp_path / "f.npy"), m)
    np.save(tmp_path / "i.npy", np.array([[1500, 0]], np.uint16))
    np.testing.assert_array_equal(io.read_depth(tmp_path / "i.npy", depth_scale_m=0.001), np.array([[1.5, np.nan]], np.float32))
    write_u16(tmp_path / "s.png", np.array([[2500, 0, 100]]))
    np.testing.assert_allclose(io.read_depth(tmp_path / "s.png", depth_scale_m=0.001), [[2.5, np.nan, 0.1]], rtol=1e-6)
    # a scale is for integers: with float depth (EXR, float NPY) or a format of fixed units it is refused by name
    for path, fmt in ((tmp_path / "d.exr", None), (tmp_path / "f.npy", None), (tmp_path / "s.png", "kitti")):
        with pytest.raises(ValueError, match="depth_scale_m applies to integer depth only"):
            io.read_depth(path, fmt, depth_scale_m=0.001)
    with pytest.raises(ValueError, match="depth_scale_m"):
        io.read_depth(tmp_path / "s.png")  # integers need their unit
    io.write_image(tmp_path / "e8.png", np.zeros((2, 2, 1), np.uint8))
    with pytest.raises(ValueError, match="8-bit"):
        io.read_depth(tmp_path / "e8.png", depth_scale_m=0.001)
    np.save(tmp_path / "neg.npy", np.array([[1.0, -2.0]], np.float32))
    with pytest.raises(ValueError, match="negative"):
        io.read_depth(tmp_path / "neg.npy")
    with pytest.raises(ValueError, match="format"):
        io.read_depth(tmp_path / "f.npy", "zed")
    with pytest.raises(ValueError, match="suffix"):
        io.read_depth(tmp_path / "x.dat")
    with pytest.raises(FileNotFoundError):
        io.read_depth(tmp_path / "missing.npy")


def test_holes_are_filled_from_the_nearest_data_or_the_sky():
    d = np.array([[np.nan, np.nan, 9.0], [1.0, np.nan, 9.0], [1.0, 1.0, np.nan]], np.float32)
    sky = np.zeros((3, 3), bool)
    sky[0, 0] = True
    out = fill_depth_holes(d, sky)
    # (0,0) is sky; (0,1) is nearest to 9 at (0,2) and 1 at (1,0)... both at distance 1 px:
    # either is a nearest pixel with data; (1,1) likewise; (2,2) nearest are (2,1)=1 and (1,2)=9
    assert out[0, 0] == np.inf
    for r, c in ((0, 1), (1, 1), (2, 2)):
        neighbours = {float(d[rr, cc]) for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)) if 0 <= rr < 3 and 0 <= cc < 3 and np.isfinite(d[rr, cc])}
        assert float(out[r, c]) in neighbours
    assert np.isfinite(out[1:]).all() and not np.isnan(out).any()
    with pytest.raises(ValueError, match="no finite depth"):
        fill_depth_holes(np.full((2, 2), np.nan, np.float32), np.zeros((2, 2), bool))
    # a photo with a sparse map: every pixel gets depth, the data kept as it was
    img = np.full((4, 5, 3), 60, np.uint8)
    sparse = np.full((4, 5), np.nan, np.float32)
    sparse[3, 0], sparse[0, 4] = 2.0, 7.0
    photo = PhotoScene(img, sparse)
    assert photo.depth_m[3, 0] == 2.0 and photo.depth_m[0, 4] == 7.0 and set(np.unique(photo.depth_m)) == {2.0, 7.0}


def test_the_field_of_view_from_exif(tmp_path):
    # a 35 mm equivalent keeps the diagonal of a 36 x 24 mm frame: 26 mm on a 4:3 photo
    diag = 2 * math.atan(math.hypot(36, 24) / (2 * 26))
    want = 2 * math.degrees(math.atan(math.tan(diag / 2) * 3 / 5))  # 4:3 -> height over diagonal 3/5
    assert exif_vertical_fov_deg({"Exif:FocalLengthIn35mmFilm": 26}, 4000, 3000) == pytest.approx(want, rel=1e-12)
    assert exif_vertical_fov_deg({}, 4000, 3000) is None
    assert exif_vertical_fov_deg({"Exif:FocalLengthIn35mmFilm": 0}, 4000, 3000) is None
    img = np.random.default_rng(0).integers(0, 255, (30, 40, 3), dtype=np.uint8)
    path = tmp_path / "p.jpg"
    io.write_image(path, img, metadata={"Exif:FocalLengthIn35mmFilm": 26})
    assert io.read_stored(path)[1]["Exif:FocalLengthIn35mmFilm"] == 26  # the file holds it
    photo = PhotoScene.read(path)
    fov = 2 * math.degrees(math.atan(math.tan(diag / 2) * 30 / math.hypot(40, 30)))
    assert photo.camera.vertical_fov_deg == pytest.approx(fov, rel=1e-9)
    assert PhotoScene.read(path, vertical_fov_deg=45.0).camera.vertical_fov_deg == 45.0


def test_the_command_line_reads_each_format_and_the_model_without_depth(tmp_path):
    from skyfall import cli, dataset

    photos, depths = tmp_path / "in", tmp_path / "depth"
    photos.mkdir()
    depths.mkdir()
    rng = np.random.default_rng(2)
    img = rng.integers(30, 220, (24, 32, 3), dtype=np.uint8)
    io.write_image(photos / "p.png", img)
    write_u16(depths / "p.png", np.full((24, 32), 5 * 256))  # KITTI: 5 m everywhere
    out = tmp_path / "kitti"
    assert cli.main(["dataset", "--input", str(photos), "--depth", str(depths), "--depth-format", "kitti", "--rain-rate", "10:10", "--layers", "rain_alpha,rain_depth_m", "--no-progress", "--out", str(out)]) == 0
    row = dataset.read_manifest(out)[0]
    assert row["status"] == "ok" and row["depth_source"] == "file" and row["depth_format"] == "kitti" and row["depth_scale_m"] is None
    assert np.nanmax(np.where(np.isinf(d := np.load(out / "items" / "000000.rain_depth_m.npy")), np.nan, d)) <= 5.0
    # no depth: the photo scene model at the distance asked for, recorded in the row
    out = tmp_path / "nodepth"
    assert cli.main(["dataset", "--input", str(photos), "--distance-m", "20", "--rain-rate", "10:10", "--no-progress", "--out", str(out)]) == 0
    row = dataset.read_manifest(out)[0]
    assert row["depth_source"] == "distance" and row["distance_m"] == 20.0 and row["fov_source"] == "default"
    # a scale with float depth is refused by name, for the item
    np.save(depths / "p.npy", np.full((24, 32), 3.0, np.float32))
    (depths / "p.png").unlink()
    out = tmp_path / "scaled"
    assert cli.main(["dataset", "--input", str(photos), "--depth", str(depths), "--depth-scale-m", "0.001", "--no-progress", "--out", str(out)]) == 3
    assert "depth_scale_m applies to integer depth only" in dataset.read_manifest(out)[0]["error"]
