"""The sky mask estimator (skyfall.photo.estimate_sky_mask) against masks known independently:
synthetic skies drawn here, and scikit-image's photos with masks drawn by hand
(tests/data/sky_masks/README.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from skimage import data

from skyfall import PhotoScene, io
from skyfall.photo import estimate_sky_mask
from skyfall.sky_mask import mask_iou

MASKS = Path(__file__).parent / "data" / "sky_masks"


def textured_ground(h: int, w: int, seed: int) -> np.ndarray:
    """A ground of noise in browns and greens, sRGB codes."""
    rng = np.random.default_rng(seed)
    base = np.array([90, 80, 60], float) + rng.normal(0, 35, (h, w, 3))
    return np.clip(base, 0, 255)


def jagged_horizon(w: int, h: int, seed: int) -> np.ndarray:
    """Each column's first ground row: a skyline of blocks between 30 % and 60 % of the height."""
    rng = np.random.default_rng(seed)
    heights = np.repeat(rng.integers(int(0.3 * h), int(0.6 * h), w // 16 + 1), 16)[:w]
    return heights


@pytest.mark.parametrize("kind", ["blue", "dusk", "overcast"])
def test_synthetic_skies_are_found_to_the_pixel(kind):
    h, w = 240, 360
    rows = np.arange(h)[:, None, None] / h
    if kind == "blue":  # a clear sky, paler toward the horizon
        sky = np.array([70, 130, 220]) + rows * np.array([90, 70, 20])
    elif kind == "dusk":  # dark blue to violet
        sky = np.array([20, 35, 80]) + rows * np.array([40, 20, 30])
    else:  # overcast: bright, nearly white, brightest of the photo
        sky = np.array([215, 218, 222]) + rows * np.array([10, 10, 8])
    sky = np.broadcast_to(sky, (h, w, 3))
    line = jagged_horizon(w, h, 1)
    truth = np.arange(h)[:, None] < line[None, :]
    img = np.where(truth[..., None], sky, textured_ground(h, w, 2)).astype(np.uint8)
    est = estimate_sky_mask(img)
    iou = mask_iou(est, truth)
    assert iou >= 0.95, iou
    # every error lies within a few px of the skyline (no blobs in the ground, no holes in the sky)
    wrong = np.argwhere(est != truth)
    if len(wrong):
        assert np.abs(wrong[:, 0] - line[wrong[:, 1]]).max() <= 12


def test_the_bundled_photos_against_hand_drawn_masks():
    # rocket: the hand mask (polygons around the towers and the rocket, the horizon's clouds
    # counted as sky); measured IoU 0.86 when this was written
    hand = io.read_stored(MASKS / "rocket.png")[0][..., 0] > 127
    est = estimate_sky_mask(data.rocket())
    assert mask_iou(est, hand) >= 0.8
    # precision: the hand polygons enclose each tower whole, while the estimate takes in the
    # sky seen through their lattices (measured 0.92)
    assert np.count_nonzero(est & hand) / np.count_nonzero(est) >= 0.9
    # the indoor photos show no sky (their hand masks are empty): the estimate finds none
    for name in ("coffee", "astronaut", "chelsea"):
        est = estimate_sky_mask(getattr(data, name)())
        assert est.mean() <= 0.005, name


def test_what_is_not_a_sky():
    flat = np.full((50, 70, 3), 200, np.uint8)  # smooth top to bottom: a wall, not a sky
    assert not estimate_sky_mask(flat).any()
    dark = np.zeros((50, 70, 3), np.uint8)
    dark[30:] = np.random.default_rng(0).integers(0, 255, (20, 70, 3))
    assert not estimate_sky_mask(dark).any()  # dark and neutral: night or a shadow
    brown = dark.copy()
    brown[:30] = (150, 90, 50)  # a smooth brown top: a table, a wall
    assert not estimate_sky_mask(brown).any()
    blue = dark.copy()
    blue[:30] = (80, 120, 200)
    m = estimate_sky_mask(blue)
    assert m[:28].all() and not m[32:].any()
    # the encoding is the caller's: linear floats, in any units, find the same sky
    np.testing.assert_array_equal(estimate_sky_mask(io.decode_srgb8(blue) * 7.0, encoding="linear"), m)
    np.testing.assert_array_equal(estimate_sky_mask(blue / 255.0, encoding="srgb"), m)


def test_bad_input_is_refused_by_name():
    with pytest.raises(ValueError, match="shape"):
        estimate_sky_mask(np.zeros((5, 5), np.uint8))
    with pytest.raises(ValueError, match="encoding"):
        estimate_sky_mask(np.zeros((5, 5, 3), np.float32))
    with pytest.raises(ValueError, match="finite"):
        estimate_sky_mask(np.full((5, 5, 3), np.nan, np.float32), encoding="linear")
    with pytest.raises(ValueError, match="max_gradient"):
        estimate_sky_mask(np.zeros((5, 5, 3), np.uint8), max_gradient=0.0)
    with pytest.raises(ValueError, match="work_px"):
        estimate_sky_mask(np.zeros((5, 5, 3), np.uint8), work_px=4)
    with pytest.raises(ValueError, match="shapes differ"):
        mask_iou(np.zeros((2, 2), bool), np.zeros((2, 3), bool))


def test_the_photo_scene_uses_one_mask_given_or_estimated():
    img = np.zeros((40, 60, 3), np.uint8)
    img[:15] = (80, 120, 200)
    img[15:] = np.random.default_rng(3).integers(0, 255, (25, 60, 3))
    photo = PhotoScene(img)
    np.testing.assert_array_equal(photo.sky_mask, estimate_sky_mask(img))
    np.testing.assert_array_equal(photo.sky_mask, np.isinf(photo.depth_m))
    mine = np.zeros((40, 60), bool)
    mine[:5] = True
    np.testing.assert_array_equal(PhotoScene(img, sky_mask=mine).sky_mask, mine)
    assert not PhotoScene(img, sky_mask=None).sky_mask.any()
    # a user's mask over a depth map: its sky, and the map's inf outside it filled as no data
    depth = np.full((40, 60), 4.0, np.float32)
    depth[:10] = np.inf
    with_map = PhotoScene(img, depth, sky_mask=mine)
    np.testing.assert_array_equal(with_map.sky_mask, mine)
    assert np.isfinite(with_map.depth_m[5:]).all()
    with pytest.raises(TypeError, match="boolean"):
        PhotoScene(img, sky_mask=mine.astype(np.uint8))
    with pytest.raises(ValueError, match="shape"):
        PhotoScene(img, sky_mask=mine[:-1])
    with pytest.raises(ValueError, match="sky_mask"):
        PhotoScene(img, sky_mask="auto")
