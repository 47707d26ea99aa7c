"""The rain's far level of detail (``Weather.rain_far_m``): its layers against the per-drop
reference, the depth test, the 8-bit path, determinism and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from skyfall import Camera, PhotoScene, Renderer, Weather, io, scenes

W, H = 320, 180


@pytest.fixture(scope="module")
def cpu() -> Renderer:
    return Renderer(W, H, backend="cpu")


def open_air(depth: float = np.inf, pitch_deg: float = 0.0) -> PhotoScene:
    img = np.full((H, W, 3), 0.1, np.float32)
    cam = Camera((0.3, 1.6, 0.2), pitch_deg=pitch_deg, vertical_fov_deg=60.0)
    return PhotoScene(img, np.full((H, W), depth, np.float32), camera=cam, encoding="linear", airlight="sky")


@pytest.mark.parametrize(
    ("pitch_deg", "wind"),
    [(0.0, (0.0, 0.0, 0.0)), (25.0, (0.0, 0.0, 0.0)), (0.0, (5.0, 0.0, 2.0))],
)
def test_the_far_layers_carry_the_per_drop_opacity(cpu, pitch_deg, wind):
    # The layers hold the far drops' expected opacity (their textures' density, the rays'
    # obliquity and the drops' off-axis projection): the frame's mean coverage matches the
    # reference's, drop for drop, over seeds (measured within about 1 %: 0.5 % at 1080p, -0.5 to
    # +0.2 % at 640 x 360, 8 seeds).
    scene = open_air(pitch_deg=pitch_deg)
    base = {"rain_rate_mm_h": 20.0, "rain_near_m": 5.0, "wind_m_s": wind, "rain_method": "drops"}
    ref = [cpu.render(scene, Weather(**base), seed=s).layers["rain_alpha"].mean() for s in range(6)]
    lod = [cpu.render(scene, Weather(**base, rain_far_m=2.0), seed=s).layers["rain_alpha"].mean() for s in range(6)]
    near_only = cpu.render(scene, Weather(**{**base, "rain_near_m": 2.0}), seed=0).layers["rain_alpha"].mean()
    assert near_only < 0.5 * np.mean(ref)  # the far part is most of the frame's rain
    assert np.mean(lod) / np.mean(ref) == pytest.approx(1.0, abs=0.08)


def test_the_scene_hides_the_far_layers(cpu):
    # A wall at depth 1.2 m hides every drop beyond it: in this 91 deg wide view no ray meets it
    # farther than 1.2·√2 < 2 m horizontally, so the far layers (from 2 m) show nowhere, and the
    # near drops are the reference's visible ones (a drop 2 m away horizontally in view is at
    # least 2/√2 m deep): the frames are the same bits.
    wall = open_air(depth=1.2)
    a = cpu.render(wall, Weather(rain_rate_mm_h=30.0, rain_method="drops"), seed=2)
    b = cpu.render(wall, Weather(rain_rate_mm_h=30.0, rain_method="drops", rain_far_m=2.0), seed=2)
    assert a.layers["rain_alpha"].max() > 0
    assert a.rgb.tobytes() == b.rgb.tobytes()
    # behind the layers' span the scene shows all of them; between, a share
    far = [cpu.render(open_air(depth=d), Weather(rain_rate_mm_h=30.0, rain_far_m=2.0), seed=2).layers["rain_alpha"].mean() for d in (3.5, np.inf)]
    assert far[0] < far[1]


def test_the_8bit_path_is_within_one_code_of_the_float_frame(cpu):
    rng = np.random.default_rng(5)
    photo = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    depth = np.where(np.arange(W)[None, :] < W // 2, 3.0, np.inf).astype(np.float32) * np.ones((H, 1), np.float32)
    scene = PhotoScene(photo, depth, camera=Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0))
    w = Weather(rain_rate_mm_h=40.0, visibility_m=800.0, rain_far_m=2.0)
    fused = cpu.render_srgb8(scene, w, seed=1)
    frame = cpu.render(scene, w, seed=1)
    diff = np.abs(fused.astype(int) - io.to_srgb8(frame.rgb).astype(int))
    assert diff.max() <= 1
    # and the layers changed the frame
    assert not np.array_equal(fused, cpu.render_srgb8(scene, Weather(rain_rate_mm_h=40.0, visibility_m=800.0, rain_far_m=2.0, rain_streaks=False), seed=1))


def test_the_far_layers_are_deterministic_and_seeded(cpu):
    w = Weather(rain_rate_mm_h=20.0, rain_far_m=2.5)
    a = cpu.render(open_air(), w, seed=9).rgb
    b = cpu.render(open_air(), w, seed=9).rgb
    c = cpu.render(open_air(), w, seed=10).rgb
    assert a.tobytes() == b.tobytes()
    assert a.tobytes() != c.tobytes()


def test_bad_far_distances_are_refused_by_name():
    with pytest.raises(ValueError, match="rain_far_m"):
        Weather(rain_rate_mm_h=5.0, rain_near_m=5.0, rain_far_m=5.0)
    with pytest.raises(ValueError, match="rain_far_m"):
        Weather(rain_rate_mm_h=5.0, rain_far_m=-1.0)
    with pytest.raises(ValueError, match="rain_far_m"):
        Weather(rain_rate_mm_h=5.0, rain_far_m=float("nan"))


def test_a_lens_refuses_the_far_layers(cpu):
    lens = Camera((0.0, 1.6, 0.0), vertical_fov_deg=60.0, f_number=2.0, focus_distance_m=5.0)
    scene = PhotoScene(np.full((H, W, 3), 0.1, np.float32), np.full((H, W), np.inf, np.float32), camera=lens, encoding="linear")
    w = Weather(rain_rate_mm_h=10.0, rain_far_m=2.0)
    with pytest.raises(ValueError, match="rain_far_m.*pinhole"):
        cpu.render(scene, w)


@pytest.mark.parametrize("wind", [0.0, 3.0])
def test_the_gpu_draws_the_far_layers_as_the_cpu_does(cpu, wind):
    """The GPU's far pass against the CPU's shells (its lookups exact per pixel where the CPU's
    are interpolated along 16-pixel runs): the street in rain, the far shells beyond 2 m and the
    near streaks over them; the frame, rain_alpha (over the whole frame and by thirds, top to
    bottom) and rain_depth_m."""
    from skimage.metrics import structural_similarity

    weather = Weather(rain_rate_mm_h=25.0, rain_near_m=6.0, rain_far_m=2.0, wind_m_s=(wind, 0.0, 0.0))
    street = scenes.street()
    c = cpu.render(street, weather, seed=4)
    g = Renderer(W, H, backend="gpu").render(street, weather, seed=4)
    c8, g8 = io.to_srgb8(c.rgb), io.to_srgb8(g.rgb)
    assert structural_similarity(c8, g8, channel_axis=2) >= 0.99
    assert np.mean(np.abs(c8.astype(int) - g8) <= 1) >= 0.999
    ca, ga = c.layers["rain_alpha"], g.layers["rain_alpha"]
    assert structural_similarity(ca, ga, data_range=1.0) >= 0.99
    for rows in np.array_split(np.arange(H), 3):
        assert ga[rows].mean() == pytest.approx(ca[rows].mean(), rel=0.02)
    cd, gd = c.layers["rain_depth_m"], g.layers["rain_depth_m"]
    same = np.isclose(cd, gd, rtol=1e-3) | (np.isinf(cd) & np.isinf(gd))
    assert same.mean() >= 0.97
    # the far shells drew: more coverage than the near streaks alone
    near = cpu.render(street, Weather(rain_rate_mm_h=25.0, rain_near_m=2.0, wind_m_s=(wind, 0.0, 0.0)), seed=4)
    assert ga.mean() > 1.2 * near.layers["rain_alpha"].mean()
