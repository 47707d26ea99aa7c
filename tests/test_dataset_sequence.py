"""skyfall.dataset with ``sequence``: each item a clip (rainy and clean MP4, layer stacks),
checked against frames rendered directly at time k / fps, across workers and after resume."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather, dataset, io, scenes
from skyfall.photo import estimate_sky_mask, sky_level_camera
from skyfall.video import read_video

W, H, N, FPS = 32, 24, 4, 12.0


def tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def rows(out: Path) -> list[dict]:
    return [r for r in dataset.read_manifest(out) if r["status"] == "ok"]


def check_row(out: Path, row: dict, layers: tuple[str, ...]) -> None:
    stem = f"{row['index']:06d}"
    assert sorted(row["files"]) == sorted([f"{stem}.clean.mp4", f"{stem}.rain.mp4", *(f"{stem}.{n}.npy" for n in layers)])
    for name, digest in row["files"].items():
        assert hashlib.sha256((out / "items" / name).read_bytes()).hexdigest() == digest, name
    assert row["sequence"] == N and row["fps"] == FPS


def weather(row: dict) -> Weather:
    p = row["params"]
    return Weather(rain_rate_mm_h=p["rain_rate_mm_h"], visibility_m=float(p["visibility_m"]), wind_m_s=(p["wind_m_s"], 0.0, 0.0), rain_near_m=row["rain_near_m"])


@pytest.fixture(scope="module")
def photos(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, np.ndarray]]:
    """A folder of two 8-bit PNG photos, and their pixels by file name."""
    folder = tmp_path_factory.mktemp("clip_photos")
    r = Renderer(W, H, backend="cpu")
    pixels = {}
    for k in range(2):
        pixels[f"p{k}.png"] = io.to_srgb8(r.render(scenes.street(seed=k)).rgb)
        io.write_image(folder / f"p{k}.png", pixels[f"p{k}.png"])
    return folder, pixels


def test_photo_clips_are_the_photo_with_rain_rendered_at_k_over_fps(photos, tmp_path):
    folder, pixels = photos
    out = tmp_path / "ds"
    s = dataset.generate(out=out, input=folder, seed=3, rain_rate_mm_h="20:60", sequence=N, fps=FPS, video_lossless=True, progress=False)
    assert (s.generated, s.errors) == (2, 0)
    r = Renderer(W, H, backend="cpu")
    for row in rows(out):
        check_row(out, row, ("rain_alpha",))
        assert row["path"] == "srgb8" and row["video_lossless"] is True
        stem = out / "items" / f"{row['index']:06d}"
        # the photo scene model without depth: the sky estimated, the camera level or pitched up
        # to it, everything else at 10 m
        level = sky_level_camera(W, H, estimate_sky_mask(pixels[row["image"]]), vertical_fov_deg=60.0)
        cam = Camera((0.0, 0.0, 0.0), pitch_deg=level.pitch_deg, vertical_fov_deg=60.0, width=W, height=H, exposure_s=row["params"]["exposure_s"])
        scene = PhotoScene(pixels[row["image"]], camera=cam)
        rainy = list(read_video(f"{stem}.rain.mp4"))
        clean = list(read_video(f"{stem}.clean.mp4"))
        assert len(rainy) == len(clean) == N and rainy[0].shape == (H, W, 3)
        alpha = np.load(f"{stem}.rain_alpha.npy")
        assert alpha.shape == (N, H, W) and alpha.dtype == np.float32
        for k in range(N):
            a = np.empty((H, W), np.float32)
            direct = r.render_srgb8(scene, weather(row), time_s=k / FPS, seed=row["params"]["render_seed"], layers={"rain_alpha": a}).image
            np.testing.assert_array_equal(rainy[k], direct)
            np.testing.assert_array_equal(alpha[k], a)
            np.testing.assert_array_equal(clean[k], pixels[row["image"]])
        assert not np.array_equal(rainy[0], rainy[1])  # the rain moves
        assert abs(row["mean_rain_alpha"] - float(alpha.mean(dtype=np.float64))) < 1e-12


def test_street_clips_and_layer_stacks_equal_direct_renders(tmp_path):
    out = tmp_path / "ds"
    layers = ("rain_alpha", "rain_depth_m", "transmittance")
    dataset.generate(out=out, scene="street", variants=2, width=W, height=H, ambient_spacing_m=8.0, visibility_m="300:3000",
                     layers=layers, sequence=N, fps=FPS, video_lossless=True, progress=False)
    street = scenes.street()
    assert street.camera is not None
    r = Renderer(W, H, backend="cpu")
    got = rows(out)
    assert len(got) == 2
    for row in got:
        check_row(out, row, layers)
        assert row["path"] == "banded"
        stem = out / "items" / f"{row['index']:06d}"
        cam = Camera(tuple(row["camera_position_m"]), yaw_deg=row["camera_yaw_deg"], pitch_deg=row["camera_pitch_deg"],
                     vertical_fov_deg=street.camera.vertical_fov_deg, exposure_s=row["params"]["exposure_s"])
        rainy = list(read_video(f"{stem}.rain.mp4"))
        stacks = {n: np.load(f"{stem}.{n}.npy") for n in layers}
        clean = io.to_srgb8(r.render(street, Weather(), camera=cam, ambient_spacing_m=8.0).rgb)
        assert all(np.array_equal(f, clean) for f in read_video(f"{stem}.clean.mp4"))
        assert len(rainy) == N
        for k in range(N):
            frame = r.render(street, weather(row), camera=cam, time_s=k / FPS, seed=row["params"]["render_seed"], ambient_spacing_m=8.0)
            np.testing.assert_array_equal(rainy[k], io.to_srgb8(frame.rgb))
            for n in layers:
                assert stacks[n].shape == (N, H, W) and stacks[n].dtype == np.float32
                np.testing.assert_array_equal(stacks[n][k], frame.layer(n))


def test_clips_are_the_same_bytes_on_two_workers_and_resume_rewrites_a_deleted_mp4(tmp_path):
    from skyfall import cli

    opts = dict(scene="street", variants=2, width=W, height=H, ambient_spacing_m=8.0, seed=7, sequence=N, fps=FPS, video_lossless=True, progress=False)
    dataset.generate(out=tmp_path / "one", **opts)
    args = ["dataset", "--scene", "street", "--variants", "2", "--width", str(W), "--height", str(H), "--ambient-spacing-m", "8", "--seed", "7",
            "--sequence", str(N), "--fps", str(FPS), "--video-lossless", "--workers", "2", "--no-progress", "--out", str(tmp_path / "two")]
    assert cli.main(args) == 0
    one = tree(tmp_path / "one")
    assert one == tree(tmp_path / "two")
    items = tmp_path / "one" / "items"
    (items / "000001.rain.mp4").unlink()
    (items / ".000000.rain.mp4.tmp-1.mp4").write_bytes(b"left by a killed run")
    s = dataset.generate(out=tmp_path / "one", resume=True, **opts)
    assert (s.generated, s.skipped) == (1, 1)
    assert tree(tmp_path / "one") == one
    config = json.loads((tmp_path / "one" / "config.json").read_text())["config"]
    assert (config["sequence"], config["fps"], config["video_lossless"]) == (N, FPS, True)
    # a clip's options do not share the stills' checksum (resume makes the items again)
    assert dataset.DatasetConfig(out="x", scene="street").sha256() != dataset.DatasetConfig(out="x", scene="street", sequence=N).sha256()


def test_lossy_clips_have_the_frames_and_are_close_to_the_lossless_ones(tmp_path):
    opts = dict(scene="street", variants=1, width=W, height=H, ambient_spacing_m=8.0, seed=7, sequence=N, fps=FPS, progress=False)
    dataset.generate(out=tmp_path / "lossy", **opts)
    dataset.generate(out=tmp_path / "exact", video_lossless=True, **opts)
    (row,) = rows(tmp_path / "lossy")
    check_row(tmp_path / "lossy", row, ("rain_alpha",))
    assert row["video_lossless"] is False
    for clip in ("rain", "clean"):
        lossy = np.array(list(read_video(tmp_path / "lossy" / "items" / f"000000.{clip}.mp4")), np.float64)
        exact = np.array(list(read_video(tmp_path / "exact" / "items" / f"000000.{clip}.mp4")), np.float64)
        assert lossy.shape == exact.shape == (N, H, W, 3)
        psnr = 10.0 * np.log10(255.0**2 / np.mean((lossy - exact) ** 2))
        assert psnr > 30.0, (clip, psnr)
    # the layer stacks do not depend on the video's encoding
    assert (tmp_path / "lossy" / "items" / "000000.rain_alpha.npy").read_bytes() == (tmp_path / "exact" / "items" / "000000.rain_alpha.npy").read_bytes()
    # in worker processes: the layer stacks are the same bytes, and the lossy clips (whose x264
    # bytes can differ between processes, see skyfall.video) decode to the same frames
    dataset.generate(out=tmp_path / "again", workers=2, **opts)
    (again,) = rows(tmp_path / "again")
    check_row(tmp_path / "again", again, ("rain_alpha",))
    assert (tmp_path / "again" / "items" / "000000.rain_alpha.npy").read_bytes() == (tmp_path / "exact" / "items" / "000000.rain_alpha.npy").read_bytes()
    for clip in ("rain", "clean"):
        lossy = np.array(list(read_video(tmp_path / "again" / "items" / f"000000.{clip}.mp4")), np.float64)
        exact = np.array(list(read_video(tmp_path / "exact" / "items" / f"000000.{clip}.mp4")), np.float64)
        psnr = 10.0 * np.log10(255.0**2 / np.mean((lossy - exact) ** 2))
        assert psnr > 30.0, (clip, psnr)


@pytest.mark.parametrize(
    "options, words",
    [
        ({"sequence": 0}, ["sequence", "[1, 10000]"]),
        ({"sequence": 4, "fps": 0.0}, ["fps", "(0, 1000]"]),
        ({"sequence": 4, "fps": 5000}, ["fps", "(0, 1000]"]),
        ({"fps": 24.0}, ["fps", "need sequence"]),
        ({"video_lossless": True}, ["video_lossless", "need sequence"]),
        ({"sequence": 4, "exr": True}, ["exr", "sequence"]),
    ],
)
def test_bad_clip_options_name_the_parameter(options, words):
    with pytest.raises(ValueError) as e:
        dataset.DatasetConfig(out="x", scene="street", **options)
    for w in words:
        assert w in str(e.value)


def test_a_clip_that_cannot_be_encoded_is_an_item_error_and_leaves_no_file(tmp_path):
    folder = tmp_path / "odd"
    folder.mkdir()
    io.write_image(folder / "odd.png", io.to_srgb8(Renderer(W - 1, H - 1, backend="cpu").render(scenes.street()).rgb))
    s = dataset.generate(out=tmp_path / "ds", input=folder, sequence=N, fps=FPS, progress=False)  # lossy: even sizes only
    assert (s.generated, s.errors) == (0, 1)
    (row,) = dataset.read_manifest(tmp_path / "ds")
    assert row["status"] == "error" and "even width and height" in row["error"]
    assert sorted(p.name for p in (tmp_path / "ds" / "items").iterdir()) == ["000000.json"]
