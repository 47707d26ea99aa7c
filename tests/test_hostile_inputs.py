"""What a hostile user tried (issue 28): each call gives a documented result or a clear,
named error, never a raw exception of a library underneath, a wrong number or a silent loss."""

from __future__ import annotations

import re
import threading
from pathlib import Path

import numpy as np
import pytest

import skyfall
from skyfall import Camera, PhotoScene, Renderer, Weather, _core, cli, io, windshield

ROOT = Path(__file__).resolve().parents[1]


def test_to_srgb8_refuses_nan_as_write_image_does(tmp_path):
    with pytest.raises(ValueError, match=r"linear: holds 1 NaN values.*nan_to_num"):
        io.to_srgb8([0.0, float("nan"), 1.0])
    with pytest.raises(ValueError, match="NaN"):
        io.write_image(tmp_path / "x.png", np.full((2, 2, 3), np.nan, np.float32))
    with pytest.raises(ValueError, match="holds 4 NaN"):  # an alpha channel too
        io.to_srgb8(np.full((1, 1, 4), np.nan, np.float32), alpha_channel=3)
    # infinities are clipped, as documented
    np.testing.assert_array_equal(io.to_srgb8([-np.inf, np.inf]), [0, 255])


def test_negative_ranges_parse_on_the_command_line(tmp_path, capsys):
    common = ["--scene", "street", "--width", "32", "--height", "24", "--variants", "2", "--ambient-spacing-m", "8", "--no-progress"]
    out = tmp_path / "neg"
    assert cli.main(["dataset", *common, "--wind-m-s", "-5:5", "--seed", "1", "--out", str(out)]) == 0
    winds = [row["params"]["wind_m_s"] for row in map(__import__("json").loads, (out / "manifest.jsonl").read_text().splitlines())]
    assert all(-5.0 <= w <= 5.0 for w in winds) and len(set(winds)) == 2
    # both ends negative, scientific notation, and the '=' spelling give the same run
    assert cli.main(["dataset", *common, "--wind-m-s", "-5e0:-1", "--out", str(tmp_path / "a")]) == 0
    assert cli.main(["dataset", *common, "--wind-m-s=-5:-1", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a" / "manifest.jsonl").read_text() == (tmp_path / "b" / "manifest.jsonl").read_text()
    # a negative value outside the range is refused by name, not by argparse
    assert cli.main(["dataset", *common, "--wind-m-s", "-70:5", "--out", str(tmp_path / "c")]) == 2
    assert "wind_m_s" in capsys.readouterr().err
    assert cli.main(["render", "--width", "32", "--height", "24", "--wind-m-s", "-3.5", "--rain-rate", "5", "--out", str(tmp_path / "r.png")]) == 0


def test_threads_sharing_one_srgb8_out_get_a_value_error():
    h, w = 180, 320
    r = Renderer(w, h, backend="cpu")
    rng = np.random.default_rng(0)
    scene = PhotoScene(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), np.full((h, w), 20.0, np.float32), camera=Camera((0.0, 1.6, 0.0)))
    weather = Weather(rain_rate_mm_h=80.0, rain_near_m=12.0)
    shared = np.empty((h, w, 3), np.uint8)
    errors: list[BaseException] = []
    stop = threading.Event()

    def renders() -> None:  # until either thread is refused, or 40 frames each
        for seed in range(40):
            if stop.is_set():
                return
            try:
                r.render_srgb8(scene, weather, seed=seed, out=shared)
            except BaseException as e:  # noqa: BLE001 - every kind is recorded and checked
                errors.append(e)
                stop.set()

    threads = [threading.Thread(target=renders) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors, "the two renders never overlapped: the test proves nothing"
    assert all(isinstance(e, ValueError) for e in errors), [repr(e) for e in errors]
    assert "out is in use elsewhere" in str(errors[0]) and "pass a separate array" in str(errors[0])


def test_metaball_radii_length_message():
    with pytest.raises(ValueError, match=r"^radii_px: has length 1, expected 2 \(one radius per row of centers_px\)$"):
        windshield.metaball_height_map([[1, 1], [2, 2]], [5.0], (8, 8))


def test_windshield_load_of_a_garbage_file_names_it(tmp_path):
    for name, data in (("garbage.npz", b"not a windshield at all"), ("empty.npz", b"")):
        p = tmp_path / name
        p.write_bytes(data)
        with pytest.raises(ValueError) as e:
            windshield.Windshield.load(p)
        assert str(p) in str(e.value) and "Windshield.save" in str(e.value), e.value
        assert "allow_pickle" not in str(e.value)
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(3))
    with pytest.raises(ValueError, match="it has no params, scalars, steps, drops, particles"):
        windshield.Windshield.load(other)
    one = tmp_path / "one.npy"
    np.save(one, np.zeros(3))
    with pytest.raises(ValueError, match="holds one array"):
        windshield.Windshield.load(one)
    with pytest.raises(FileNotFoundError):
        windshield.Windshield.load(tmp_path / "missing.npz")
    # a real one still loads
    w = windshield.Windshield(rain_rate_mm_h=10.0, glass_width_mm=100.0, glass_height_mm=80.0, wipers=0)
    w.step(0.2)
    w.save(tmp_path / "w.npz")
    assert windshield.Windshield.load(tmp_path / "w.npz").water_kg() == w.water_kg()


def test_read_video_of_a_garbage_file_names_it(tmp_path):
    from skyfall import video

    p = tmp_path / "garbage.mp4"
    p.write_bytes(b"\x00\x01 not a video" * 100)
    with pytest.raises(ValueError) as e:
        list(video.read_video(p))
    assert str(p) in str(e.value) and "not a video" in str(e.value)
    assert type(e.value) is ValueError  # not av's own error type
    with pytest.raises(FileNotFoundError):
        list(video.read_video(tmp_path / "missing.mp4"))


def test_integer_parameters_print_as_integers():
    for name, value, want in (("width", 20000.0, "width = 20000 is"), ("n_particles", 0.0, "n_particles = 0 is"),
                              ("samples", 2.0, "samples = 2 is"), ("seed", -1.0, "seed = -1 is"),
                              ("width", 2.5e4 + 0.5, "width = 25000.5 is"), ("width", float("nan"), "width = NaN is"),
                              ("rain_rate_mm_h", 600.0, "rain_rate_mm_h = 600.0 is")):
        with pytest.raises(ValueError) as e:
            _core.check_range(name, value, None)
        assert str(e.value).startswith(want), e.value
    from skyfall import clouds

    with pytest.raises(ValueError, match=r"^n_particles = 0 is outside the valid range \[1, 1e6\]$"):
        clouds.particles("cumulus", n_particles=0)


def test_the_glass_range_and_its_cell_limit_agree_and_say_which_limit():
    with pytest.raises(ValueError) as e:
        windshield.Windshield(glass_width_mm=4000.0, glass_height_mm=4000.0, cell_mm=0.5)
    msg = str(e.value)
    assert msg.startswith("cell_mm = 0.5 mm makes a glass of 8000 × 8000 = 64000000 cells, over the limit of 4000000 cells"), msg
    assert "cell_mm ≥ 2 mm" in msg
    # the least cell it names is accepted; the documented corners within the limit work
    windshield.Windshield(glass_width_mm=4000.0, glass_height_mm=4000.0, cell_mm=2.0, wipers=0)
    windshield.Windshield(glass_width_mm=1000.0, glass_height_mm=1000.0, cell_mm=0.5, wipers=0)
    assert "4e6 cells" in (windshield.Windshield.__doc__ or "")


def test_the_largest_documented_frame_is_within_the_frame_budget():
    # 16384 x 16384 with rgb, depth and every layer: the budget was 4 GiB and refused it
    assert 16384 * 16384 * 8 * 4 <= _core.FRAME_BUDGET_BYTES
    lo, hi, *_ = _core.RANGES["width"]
    assert hi == 16384


def test_the_readme_references_describe_what_is_drawn():
    text = (ROOT / "README.md").read_text()
    refs = text[text.index("## References") :]
    assert "not yet" not in refs, re.findall(r".*not yet.*", refs)
    assert "Weather(clouds=...)" in refs and "snow/cover/" in refs
    assert skyfall.Weather(clouds="broken").clouds is not None  # clouds are drawn in frames
