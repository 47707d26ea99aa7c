"""skyfall.augment (image in, image out) against the renderer it wraps, and the albumentations
adapter through albumentations itself (Compose's seed, to_dict / from_dict, the depth target)."""

from __future__ import annotations

import json
import math

import albumentations as A
import numpy as np
import pytest
from skimage import data, transform

from skyfall import Camera, PhotoScene, Renderer, Weather, augment
from skyfall.adapters import AlbumentationsWeather
from skyfall.augmentation import draw


def small(image: np.ndarray, width: int) -> np.ndarray:
    h = round(image.shape[0] * width / image.shape[1])
    return np.round(transform.resize(image, (h, width), anti_aliasing=True) * 255).astype(np.uint8)


COFFEE = small(data.coffee(), 120)
CAT = small(data.chelsea(), 96)


def test_one_image_is_the_renderers_frame_of_its_photo_scene():
    h, w = COFFEE.shape[:2]
    direct = Renderer(w, h, backend="cpu").render_srgb8(PhotoScene(COFFEE), Weather(rain_rate_mm_h=25.0), seed=4)
    np.testing.assert_array_equal(augment(COFFEE, rain_rate_mm_h=25.0, seed=4), direct)
    # with a depth map and a camera field
    depth = np.full((h, w), 3.0, np.float32)
    cam_scene = PhotoScene(COFFEE, depth)
    cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=cam_scene.camera.vertical_fov_deg, exposure_s=0.004)
    want = Renderer(w, h, backend="cpu").render_srgb8(PhotoScene(COFFEE, depth, camera=cam), Weather(rain_rate_mm_h=10.0), seed=2)
    np.testing.assert_array_equal(augment(COFFEE, depth_m=depth, exposure_s=0.004, rain_rate_mm_h=10.0, seed=2), want)


def test_ranges_are_drawn_from_the_seed_alone_and_recorded():
    a = draw({"rain_rate_mm_h": (1.0, 50.0), "visibility_m": (200.0, 5000.0), "wind_m_s": (-5.0, 5.0)}, seed=11)
    b = draw({"wind_m_s": (-5.0, 5.0), "visibility_m": (200.0, 5000.0), "rain_rate_mm_h": (1.0, 50.0)}, seed=11)
    assert a == b  # the order the caller names them in does not matter
    # the documented laws, against numpy's own draws in name order
    rng = np.random.default_rng(11)
    assert a["rain_rate_mm_h"] == rng.uniform(1.0, 50.0)
    assert a["visibility_m"] == pytest.approx(math.exp(rng.uniform(math.log(200.0), math.log(5000.0))), rel=1e-12)
    assert a["wind_m_s"] == (rng.uniform(-5.0, 5.0), 0.0, 0.0)
    wet, layers = augment(COFFEE, rain_rate_mm_h=(1.0, 50.0), visibility_m=(200.0, 5000.0), seed=11, return_layers=True)
    assert layers.params == {"rain_rate_mm_h": a["rain_rate_mm_h"], "visibility_m": a["visibility_m"], "seed": 11}
    h, w = COFFEE.shape[:2]
    direct = Renderer(w, h, backend="cpu").render_srgb8(PhotoScene(COFFEE), Weather(rain_rate_mm_h=a["rain_rate_mm_h"], visibility_m=a["visibility_m"]), seed=11)
    np.testing.assert_array_equal(wet, direct)
    with pytest.raises(ValueError, match="log-uniformly"):
        draw({"visibility_m": (0.0, 10.0)}, seed=0)
    with pytest.raises(ValueError, match="lo <= hi"):
        draw({"rain_rate_mm_h": (5.0, 1.0)}, seed=0)


def test_batches_lists_alpha_and_floats_keep_their_form():
    batch = np.stack([COFFEE, COFFEE[::-1]])
    out = augment(batch, rain_rate_mm_h=(5.0, 30.0), seed=3)
    assert out.shape == batch.shape and out.dtype == np.uint8
    for k in range(2):  # image k is the image alone with seed + k
        np.testing.assert_array_equal(out[k], augment(batch[k], rain_rate_mm_h=(5.0, 30.0), seed=3 + k))
    images, layers = augment([COFFEE, CAT], rain_rate_mm_h=20.0, seed=0, return_layers=True)
    assert [i.shape for i in images] == [COFFEE.shape, CAT.shape] and [lay["rain_alpha"].shape for lay in layers] == [COFFEE.shape[:2], CAT.shape[:2]]
    rgba = np.dstack([COFFEE, np.arange(COFFEE[..., 0].size, dtype=np.uint32).reshape(COFFEE.shape[:2]).astype(np.uint8)])
    out = augment(rgba, rain_rate_mm_h=20.0, seed=0)
    assert out.shape == rgba.shape
    np.testing.assert_array_equal(out[..., 3], rgba[..., 3])  # the alpha passes through
    np.testing.assert_array_equal(out[..., :3], augment(COFFEE, rain_rate_mm_h=20.0, seed=0))
    f = augment(COFFEE.astype(np.float32) / 255.0, encoding="srgb", rain_rate_mm_h=20.0, seed=0)
    assert f.dtype == np.float32 and 0.0 <= f.min() and f.max() <= 1.0
    assert np.abs(f * 255.0 - augment(COFFEE, rain_rate_mm_h=20.0, seed=0)).max() <= 1.0 + 1e-3  # the 8-bit path within a code
    with pytest.raises(ValueError, match="encoding"):
        augment(COFFEE.astype(np.float32) / 255.0, rain_rate_mm_h=1.0)
    with pytest.raises(TypeError, match="unknown weather or camera fields"):
        augment(COFFEE, rain_mm_h=5.0)
    with pytest.raises(ValueError, match="shape"):
        augment(COFFEE[..., 0], rain_rate_mm_h=5.0)


def test_the_layers_are_the_frames():
    h, w = CAT.shape[:2]
    out, layers = augment(CAT, rain_rate_mm_h=30.0, visibility_m=500.0, seed=5, return_layers=True)
    direct = np.empty((h, w), np.float32)
    Renderer(w, h, backend="cpu").render_srgb8(PhotoScene(CAT), Weather(rain_rate_mm_h=30.0, visibility_m=500.0), seed=5, layers={"rain_alpha": direct})
    np.testing.assert_array_equal(layers["rain_alpha"], direct)
    np.testing.assert_array_equal(layers["depth_m"], PhotoScene(CAT).depth_m)


def pipeline(seed: int | None = 7) -> A.Compose:
    return A.Compose([AlbumentationsWeather(rain_rate_mm_h=(5.0, 40.0), visibility_m=(300.0, 3000.0), p=1.0), A.HorizontalFlip(p=0.5)], seed=seed)


def test_the_albumentations_transform_is_reproducible_under_compose():
    first = [pipeline()(image=COFFEE) for _ in range(1)][0]
    again = pipeline()(image=COFFEE)
    np.testing.assert_array_equal(first["image"], again["image"])
    np.testing.assert_array_equal(first["rain_alpha"], again["rain_alpha"])
    assert first["image"].shape == COFFEE.shape and first["rain_alpha"].shape == COFFEE.shape[:2]
    pipe = pipeline()
    calls = [pipe(image=COFFEE)["image"] for _ in range(3)]
    assert not np.array_equal(calls[0], calls[1]) or not np.array_equal(calls[1], calls[2])  # each call draws anew
    other = pipeline(seed=8)(image=COFFEE)
    assert not np.array_equal(other["image"], first["image"])


def test_the_albumentations_transform_serialises_and_takes_depth(tmp_path):
    pipe = pipeline()
    text = json.dumps(A.to_dict(pipe))
    back = A.from_dict(json.loads(text))
    assert type(back.transforms[0]) is AlbumentationsWeather and back.transforms[0].visibility_m == (300.0, 3000.0)
    back.set_random_seed(7)
    np.testing.assert_array_equal(back(image=COFFEE)["image"], pipeline()(image=COFFEE)["image"])
    depth = np.full(COFFEE.shape[:2], 2.0, np.float32)
    out = A.Compose([AlbumentationsWeather(rain_rate_mm_h=20.0, visibility_m=50.0, layers=("rain_alpha", "depth_m"))], seed=1)(image=COFFEE, depth=depth)
    np.testing.assert_array_equal(out["depth"], depth)
    np.testing.assert_array_equal(out["depth_m"], depth)  # the scene used the given depth
    floats = A.Compose([AlbumentationsWeather(rain_rate_mm_h=20.0)], seed=1)(image=COFFEE.astype(np.float32) / 255.0)
    assert floats["image"].dtype == np.float32 and floats["image"].max() <= 1.0
