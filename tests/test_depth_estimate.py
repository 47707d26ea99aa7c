"""skyfall.depth without a network: its plumbing through a tiny ONNX graph built here (the
pre- and post-processing, resizing back, the session cache, determinism), its calibration on
synthetic depth of a known scale and shift, and the error a user without the model meets."""

from __future__ import annotations

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper

from skyfall import PhotoScene, dataset, depth, io
from skyfall.photo import ground_plane_depth, level_camera


@pytest.fixture(scope="module")
def red_graph(tmp_path_factory: pytest.TempPathFactory):
    """An ONNX graph (1, 3, h, w) -> (1, h, w): the normalised red channel, as a network's map."""
    x = helper.make_tensor_value_info("pixel_values", TensorProto.FLOAT, [1, 3, "h", "w"])
    y = helper.make_tensor_value_info("predicted_depth", TensorProto.FLOAT, [1, "h", "w"])
    index = helper.make_tensor("red", TensorProto.INT64, [], [0])
    node = helper.make_node("Gather", ["pixel_values", "red"], ["predicted_depth"], axis=1)
    graph = helper.make_graph([node], "red", [x], [y], initializer=[index])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    onnx.checker.check_model(model)
    path = tmp_path_factory.mktemp("onnx") / "red.onnx"
    onnx.save(model, str(path))
    return path


def test_the_network_sees_the_normalised_photo_and_its_map_comes_back_at_the_photo_size(red_graph):
    h, w = 90, 160
    img = np.zeros((h, w, 3), np.uint8)
    img[..., 0] = np.round(np.linspace(0, 255, w))[None, :]  # a ramp in x: linear, so bilinear keeps it
    out = depth.relative_inverse_depth(img, model=red_graph)
    assert out.shape == (h, w) and out.dtype == np.float32
    want = (img[..., 0] / 255.0 - 0.485) / 0.229  # ImageNet normalisation of the red channel
    inner = (slice(None), slice(8, -8))  # away from the edges, where resampling clamps
    np.testing.assert_allclose(out[inner], want[inner], atol=0.03)
    assert (np.diff(out[h // 2]) >= -1e-6).all() and np.ptp(out[:, w // 2]) < 1e-5  # along x, not y
    # the same bits again, and the session made once
    np.testing.assert_array_equal(depth.relative_inverse_depth(img, model=red_graph), out)
    assert depth._session(red_graph, 1) is depth._session(red_graph, 1)


def test_the_input_size_is_the_networks(red_graph, monkeypatch):
    seen = []
    real = depth._resize

    def spy(a, shape):
        seen.append(shape)
        return real(a, shape)

    monkeypatch.setattr(depth, "_resize", spy)
    depth.relative_inverse_depth(np.zeros((300, 451, 3), np.uint8), model=red_graph)
    to_net = seen[0]
    assert to_net[0] % 14 == 0 and to_net[1] % 14 == 0 and min(to_net) == 518  # short side 518, multiples of 14
    assert abs(to_net[1] / to_net[0] - 451 / 300) < 0.03  # the aspect kept
    assert seen[-1] == (300, 451)  # and back


def synthetic_scene(h: int = 120, w: int = 160):
    """A level ground seen from 1.6 m with its horizon at row 40, a box 6 m away standing on
    it, and sky above: the true depth."""
    cam = level_camera(w, h, camera_height_m=1.6, horizon_row=40.0, vertical_fov_deg=60.0)
    z = ground_plane_depth(cam).astype(np.float64)
    z[20:70, 60:100] = np.minimum(z[20:70, 60:100], 6.0)  # an upright box
    return cam, z


def test_the_calibration_recovers_a_known_scale_and_shift():
    cam, z = synthetic_scene()
    s, t = 3.7, 0.12
    rel = s / z + t  # sky: 1/inf = 0, so r = t there
    out, s_fit, t_fit = depth.to_metres(rel, camera=cam)
    assert s_fit == pytest.approx(s, rel=1e-9) and t_fit == pytest.approx(t, abs=1e-9)
    finite = np.isfinite(z)
    np.testing.assert_allclose(out[finite], z[finite], rtol=1e-6)
    assert np.isinf(out[~finite]).all()
    # a car on the ground (nearer than the plane) is trimmed out of the fit
    noisy = rel.copy()
    noisy[100:115, 20:60] += 0.5
    _, s2, t2 = depth.to_metres(noisy, camera=cam)
    assert s2 == pytest.approx(s, rel=1e-6) and t2 == pytest.approx(t, abs=1e-6)
    # a distance alone: no shift, the median at that distance
    d, s3, t3 = depth.to_metres(s / z, distance_m=5.0)
    assert t3 == 0.0 and np.median(d) == pytest.approx(5.0, rel=1e-6)
    np.testing.assert_allclose(d[finite] / z[finite], 5.0 / np.median(z), rtol=1e-5)  # one scale for all
    # both: the ground and a consistent median agree with the truth
    both, s4, t4 = depth.to_metres(rel, camera=cam, distance_m=float(np.median(z[finite])))
    assert s4 == pytest.approx(s, rel=1e-3) and t4 == pytest.approx(t, abs=1e-3)
    with pytest.raises(ValueError, match="camera"):
        depth.to_metres(rel)


def test_estimate_plugs_into_a_photo_scene():
    cam, z = synthetic_scene()
    img = np.full((120, 160, 3), 90, np.uint8)
    rel = 2.0 / z + 0.05
    d = depth.estimate(img, model=lambda _: rel, camera_height_m=1.6, horizon_row=40.0)
    photo = PhotoScene(img, d, camera=cam)
    finite = np.isfinite(z)
    np.testing.assert_allclose(photo.depth_m[finite], z[finite], rtol=1e-5)
    np.testing.assert_array_equal(photo.sky_mask, ~finite)
    with pytest.raises(ValueError, match="2-D"):
        depth.estimate(img, model=lambda _: np.zeros(3))
    with pytest.raises(TypeError, match="model"):
        depth.estimate(img, model=3)


def test_without_the_model_and_offline_the_error_says_what_to_do(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYFALL_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")
    import huggingface_hub.constants as hc

    monkeypatch.setattr(hc, "HF_HUB_OFFLINE", True)
    with pytest.raises(OSError) as err:
        depth.estimate(np.zeros((20, 30, 3), np.uint8))
    msg = str(err.value)
    assert "skyfall[depth]" in msg and "depth-anything-v2-small" in msg and str(tmp_path / "cache" / "models") in msg


def test_a_dataset_with_estimated_depth(red_graph, tmp_path):
    img = tmp_path / "in"
    img.mkdir()
    rng = np.random.default_rng(4)
    for name in ("p", "q"):
        io.write_image(img / f"{name}.png", rng.integers(20, 235, (36, 48, 3), dtype=np.uint8))
    out = tmp_path / "out"
    s = dataset.generate(out=out, input=img, depth="estimate", depth_model=str(red_graph), distance_m=8.0, variants=2, layers=("rain_alpha", "transmittance"), progress=False)
    assert (s.generated, s.errors) == (4, 0)
    rows = dataset.read_manifest(out)
    assert all(r["depth_source"] == "estimate" and r["depth_model"] == str(red_graph) for r in rows)
    again = tmp_path / "again"
    dataset.generate(out=again, input=img, depth="estimate", depth_model=str(red_graph), distance_m=8.0, variants=2, layers=("rain_alpha", "transmittance"), progress=False)
    for k in range(4):
        a = np.load(out / "items" / f"{k:06d}.transmittance.npy")
        np.testing.assert_array_equal(a, np.load(again / "items" / f"{k:06d}.transmittance.npy"))
    with pytest.raises(ValueError, match="depth_model needs depth='estimate'"):
        dataset.generate(out=tmp_path / "x", input=img, depth_model="m.onnx", progress=False)
