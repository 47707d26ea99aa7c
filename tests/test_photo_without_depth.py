"""A photo without a depth map keeps its content: scikit-image's photos under rain, snow and
clouds, judged against the clean photo by scikit-image's SSIM; and the rain still shows."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from skimage import data, transform
from skimage.metrics import structural_similarity as ssim

from skyfall import PhotoScene, Renderer, Weather, dataset, io, snow
from skyfall.photo import NEUTRAL_GUARD

INDOOR = ("coffee", "astronaut", "chelsea")


def top_ssim(a: np.ndarray, b: np.ndarray) -> float:
    h = a.shape[0] // 2
    return float(ssim(a[:h], b[:h], channel_axis=2))


@pytest.mark.parametrize("name", INDOOR)
@pytest.mark.parametrize("rate", [0.5, 25.0])
def test_the_upper_half_keeps_its_structure_and_the_rain_shows(name, rate):
    photo = getattr(data, name)()
    h, w = photo.shape[:2]
    scene = PhotoScene(photo)
    assert scene.depth_source == "distance" and not scene.sky_mask.any()  # no sky in these
    r = Renderer(w, h, backend="cpu")
    alpha = np.empty((h, w), np.float32)
    rainy = r.render_srgb8(scene, Weather(rain_rate_mm_h=rate), seed=1, layers={"rain_alpha": alpha}).image
    # the issue measured 0.40-0.49 here at 25 mm/h with the old ground-plane default
    assert top_ssim(photo, rainy) >= 0.8
    top = slice(0, h // 2)
    assert rainy[top].std() >= 0.8 * photo[top].std()  # its contrast kept (0.28-0.74 of it before)
    # the rain shows: drops cover the frame, and the pixels under the densest streaks brighten
    # more than those under the thinnest (measured at 25 mm/h: coffee 4.7 codes, astronaut
    # 10.0; chelsea 0.6: its brightest pixels, hence its airlight, are mid-grey, the streaks as
    # bright as the fur behind them; the README says so)
    assert (alpha > 0).mean() > (0.1 if rate < 1 else 0.9)
    if rate > 1 and name != "chelsea":
        lift = (rainy.astype(float) - photo).mean(axis=2)
        dense, thin = alpha >= np.quantile(alpha, 0.99), alpha <= np.quantile(alpha, 0.1)
        assert lift[dense].mean() - lift[thin].mean() >= 4.0


def test_an_airlight_without_sky_is_never_the_foregrounds_colour():
    # coffee: He, Sun & Tang's pick is the table's brown or the cup's white; the airlight is grey
    # or near it, never more saturated than the guard
    for name in ("coffee", "chelsea"):
        a = np.array(PhotoScene(getattr(data, name)()).airlight_linear)
        assert (a.max() - a.min()) / a.max() <= NEUTRAL_GUARD + 1e-6, (name, a)


def small(image: np.ndarray, width: int) -> np.ndarray:
    h = round(image.shape[0] * width / image.shape[1])
    return np.round(transform.resize(image, (h, width), anti_aliasing=True) * 255).astype(np.uint8)


def test_the_readmes_rocket_keeps_its_towers():
    # PhotoScene(rocket, camera_height_m=1.6, horizon_row=100) turned the towers into a grey
    # wall at 5 mm/h: everything above the horizon was sky
    rocket = data.rocket()
    hand = io.read_stored(Path(__file__).parent / "data" / "sky_masks" / "rocket.png")[0][..., 0] > 127
    h, w = rocket.shape[:2]
    scene = PhotoScene(rocket, camera_height_m=1.6, horizon_row=100)
    out = Renderer(w, h, backend="cpu").render_srgb8(scene, Weather(rain_rate_mm_h=5.0), seed=0)
    towers = ~hand
    towers[395:] = False  # the hand mask's ground
    # the towers and the rocket (not sky by the hand mask) keep their pixels within a few codes
    diff = np.abs(out[towers].astype(int) - rocket[towers].astype(int))
    assert np.median(diff) <= 3
    assert not scene.sky_mask[towers].mean() > 0.1


def test_snow_and_clouds_on_a_photo_without_depth():
    photo = small(data.rocket(), 200)
    h, w = photo.shape[:2]
    scene = PhotoScene(photo)
    r = Renderer(w, h, backend="cpu")
    # clouds only where there is sky, behind the towers
    frame = r.render(scene, Weather(rain_rate_mm_h=1.0, clouds="broken"), seed=0)
    cloud = frame.layers["cloud_alpha"]
    assert cloud[~scene.sky_mask].max() == 0.0 and cloud[scene.sky_mask].max() > 0.5
    # snow on the coffee: a cover needs surfaces facing up (a depth map or the ground plane);
    # without them nothing lies, and the photo is not painted over
    coffee = small(data.coffee(), 200)
    hc, wc = coffee.shape[:2]
    cscene = PhotoScene(coffee)
    weather = Weather(snow_rate_mm_h=2.0)
    cover = snow.accumulate(cscene, weather, duration_s=3 * 3600.0, dt_s=1800.0, resolution_m=0.25)
    out = Renderer(wc, hc, backend="cpu").render_srgb8(cscene, dataclasses.replace(weather, snow_cover=cover), seed=0)
    assert top_ssim(coffee, out) >= 0.75
    assert out.std() >= 0.7 * coffee.std()  # not one flat colour (the brown slab)
    # with the ground plane the ground takes snow
    ground = PhotoScene(coffee, camera_height_m=1.6, horizon_row=0.3 * hc)
    cover = snow.accumulate(ground, weather, duration_s=3 * 3600.0, dt_s=1800.0, resolution_m=0.25)
    f = Renderer(wc, hc, backend="cpu").render(ground, dataclasses.replace(weather, snow_cover=cover), seed=0)
    assert f.layers["snow_depth_m"][-10:].mean() > 0.0


def test_the_gpu_draws_the_same_photo_scene():
    photo = small(data.rocket(), 160)
    h, w = photo.shape[:2]
    scene = PhotoScene(photo)
    weather = Weather(rain_rate_mm_h=10.0)
    cpu = Renderer(w, h, backend="cpu").render(scene, weather, seed=3)
    gpu = Renderer(w, h, backend="gpu").render(scene, weather, seed=3)
    for name in ("transmittance", "rain_alpha"):
        np.testing.assert_allclose(gpu.layers[name], cpu.layers[name], atol=2e-3)
    assert ssim(io.to_srgb8(cpu.rgb), io.to_srgb8(gpu.rgb), channel_axis=2) > 0.99


def test_a_folder_of_ordinary_photos_becomes_a_rainy_dataset(tmp_path):
    folder = tmp_path / "photos"
    folder.mkdir()
    photos = {n: small(getattr(data, n)(), 160) for n in (*INDOOR, "rocket")}
    for n, p in photos.items():
        io.write_image(folder / f"{n}.png", p)
    out = tmp_path / "out"
    s = dataset.generate(out=out, input=folder, rain_rate_mm_h="20:30", variants=1, seed=1, progress=False)
    assert (s.generated, s.errors) == (4, 0)
    for row in dataset.read_manifest(out):
        assert row["status"] == "ok" and row["depth_source"] == "distance" and row["distance_m"] == 10.0
        name = row["image"][:-4]
        rainy = io.read_stored(out / "items" / f"{row['index']:06d}.rain.png")[0]
        if name in INDOOR:
            assert row["sky_share"] == 0.0
            assert top_ssim(photos[name], rainy) >= 0.8
        else:
            assert row["sky_share"] > 0.4


def test_huge_and_rgba_photos_are_refused_before_any_copy():
    # a copy would need 27.9 GiB (MemoryError, or minutes): the shape alone refuses it
    with pytest.raises(ValueError, match=r"100000x100000 px: a photo's width and height lie within \[1, 16384\]"):
        PhotoScene(np.broadcast_to(np.uint8(7), (100_000, 100_000, 3)))  # 27.9 GiB if copied
    with pytest.raises(ValueError, match="RGBA"):
        PhotoScene(np.zeros((8, 8, 4), np.uint8))
