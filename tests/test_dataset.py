"""skyfall.dataset: inputs, outputs, manifest rows, per-item sampling, byte identity across
workers and alone, resume after corruption and after a real ``kill -9``."""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from skyfall import Renderer, dataset, io, scenes
from skyfall.dataset.sample import DatasetConfig, sample_item

W, H = 64, 48


def tree(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` by relative path, with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def photos(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A folder of 64 x 48 photos and one of depth maps in each format, plus the bad cases:
    d.png has no depth map, e.png is not an image, f.png's depth map has the wrong shape."""
    root = tmp_path_factory.mktemp("photos")
    img, dep = root / "img", root / "depth"
    img.mkdir()
    dep.mkdir()
    r = Renderer(W, H, backend="cpu")
    for k, name in enumerate("abcdf"):
        frame = r.render(scenes.street(seed=k))
        io.write_image(img / f"{name}.png", io.to_srgb8(frame.rgb))
        depth = frame.depth_m
        if name == "a":
            io.write_image(dep / "a.exr", depth, channel_names=["depth_m"])
        elif name == "b":
            np.save(dep / "b.npy", depth)
        elif name == "c":
            io.write_image(dep / "c.png", (np.clip(depth, 0, 60) * 1000).astype(np.uint16))
        elif name == "f":
            np.save(dep / "f.npy", depth[:-1])
    (img / "e.png").write_bytes(b"not a png at all")
    np.save(dep / "e.npy", np.ones((H, W), np.float32))
    return img, dep


def check_checksums(out: Path, rows: list[dict]) -> None:
    for row in rows:
        for name, digest in row.get("files", {}).items():
            assert hashlib.sha256((out / "items" / name).read_bytes()).hexdigest() == digest, name


def test_a_folder_of_photos_with_depth_maps_in_every_format(photos, tmp_path):
    img, dep = photos
    out = tmp_path / "out"
    s = dataset.generate(
        out=out, input=img, depth=dep, depth_scale_m=0.001, variants=2, seed=5, visibility_m="300:3000",
        layers=("rain_alpha", "rain_depth_m", "transmittance"), progress=False,
    )
    assert (s.items, s.generated, s.errors) == (12, 2, 10)  # an error is not generated; c.png alone has integer depth
    rows = dataset.read_manifest(out)
    assert [r["index"] for r in rows] == list(range(12))
    by_image = {r["image"]: r for r in rows if r["index"] % 2 == 0}
    # a scale applies to integer depth only: the float maps (EXR, float NPY) refuse it by name
    assert {k for k, r in by_image.items() if r["status"] == "ok"} == {"c.png"}
    for name in ("a.png", "b.png"):
        assert "depth_scale_m applies to integer depth only" in by_image[name]["error"]
    unscaled = dataset.generate(
        out=tmp_path / "unscaled", input=img, depth=dep, variants=2, seed=5, visibility_m="300:3000",
        layers=("rain_alpha", "rain_depth_m", "transmittance"), progress=False,
    )
    assert unscaled.errors == 8
    plain = {r["image"]: r for r in dataset.read_manifest(tmp_path / "unscaled") if r["index"] % 2 == 0}
    assert {k for k, r in plain.items() if r["status"] == "ok"} == {"a.png", "b.png"}
    assert "depth_scale_m" in plain["c.png"]["error"]
    assert "no depth map for d.png" in by_image["d.png"]["error"]
    assert by_image["e.png"]["error"].startswith("OSError")
    assert "shape" in plain["f.png"]["error"]
    for out, rows in ((out, rows), (tmp_path / "unscaled", dataset.read_manifest(tmp_path / "unscaled"))):
        check_checksums(out, rows)
        for row in rows:
            if row["status"] != "ok":
                assert not any((out / "items").glob(f"{row['index']:06d}.*.png"))  # nothing for a failed item
                continue
            assert row["depth_source"] == "file" and row["path"] == "banded"  # layers the fused path does not fill
            p = row["params"]
            assert 1.0 <= p["rain_rate_mm_h"] <= 50.0 and 300.0 <= p["visibility_m"] <= 3000.0
            stem = out / "items" / f"{row['index']:06d}"
            rain = io.read_image(f"{stem}.rain.png")
            assert rain.shape == (H, W, 3)
            # the clean image is the photo itself
            clean = io.read_image(f"{stem}.clean.png")
            np.testing.assert_array_equal(clean, io.read_image(img / row["image"]))
            alpha = np.load(f"{stem}.rain_alpha.npy")
            t = np.load(f"{stem}.transmittance.npy")
            assert alpha.shape == t.shape == (H, W) and alpha.dtype == np.float32
            assert 0.0 <= alpha.min() and alpha.max() <= 1.0
            assert 0.0 < t.min() and t.max() < 1.0  # finite visibility hazes every pixel
            assert abs(row["mean_rain_alpha"] - float(alpha.mean(dtype=np.float64))) < 1e-12


def test_without_depth_the_ground_plane_and_the_fast_8bit_path(photos, tmp_path):
    img, _ = photos
    out = tmp_path / "out"
    s = dataset.generate(out=out, input=img, variants=1, camera_height_m=2.0, horizon_row=20.0, progress=False)
    assert (s.items, s.errors) == (6, 1)  # e.png only: without a depth folder nothing is missing
    rows = [r for r in dataset.read_manifest(out) if r["status"] == "ok"]
    assert len(rows) == 5
    for r in rows:
        assert r["depth_source"] == "ground_plane" and r["camera_height_m"] == 2.0 and r["horizon_row"] == 20.0
        assert r["path"] == "srgb8"
        assert sorted(r["files"]) == [f"{r['index']:06d}.{n}" for n in ("clean.png", "rain.png", "rain_alpha.npy")]
    check_checksums(out, rows)


def test_sampling_depends_on_the_seed_and_index_only():
    a = DatasetConfig(out="x", scene="street", variants=3, seed=9, rain_rate_mm_h="2:40", exposure_s="0.001:0.03", f_number="1.4:8")
    b = DatasetConfig(out="y", scene="street", variants=300, seed=9, rain_rate_mm_h="2:40", exposure_s="0.001:0.03", f_number="1.4:8")
    assert [sample_item(a, i) for i in range(3)] == [sample_item(b, i) for i in range(3)]
    # the documented source of randomness: SeedSequence([seed, index])
    rng = np.random.default_rng(np.random.SeedSequence([9, 2]))
    assert sample_item(a, 2).render_seed == int(rng.integers(0, 2**63 - 1))
    ps = [sample_item(b, i) for i in range(300)]
    rates = np.array([p.rain_rate_mm_h for p in ps])
    assert 2.0 <= rates.min() and rates.max() <= 40.0 and np.ptp(rates) > 30.0
    fn = np.array([p.f_number for p in ps])
    assert 1.4 <= fn.min() and fn.max() <= 8.0
    assert all(p.focus_distance_m == math.inf for p in ps)
    c = DatasetConfig(out="z", scene="street", seed=10)
    assert sample_item(c, 2) != sample_item(DatasetConfig(out="z", scene="street", seed=9), 2)


@pytest.mark.parametrize(
    "options, words",
    [
        ({"rain_rate_mm_h": "1:600"}, ["rain_rate_mm_h", "500"]),
        ({"rain_rate_mm_h": "9:2"}, ["rain_rate_mm_h", "lo must be at most hi"]),
        ({"exposure_s": "fast"}, ["exposure_s", "lo:hi"]),
        ({"f_number": "0.1:2"}, ["f_number", "0.5"]),
        ({"png_compression": 12}, ["png_compression", "[0, 9]"]),
        ({"layers": ("rain_alpha", "snow")}, ["layers", "snow"]),
        ({"focus_distance_m": "2:10"}, ["focus_distance_m needs f_number"]),
        ({"rain_far_m": 6.0}, ["rain_far_m", "rain_near_m"]),
        ({"rain_far_m": 2.0, "f_number": "2:4"}, ["rain_far_m", "f_number"]),
    ],
)
def test_bad_options_name_the_parameter_and_its_range(options, words):
    with pytest.raises(ValueError) as e:
        DatasetConfig(out="x", scene="street", **options)
    for w in words:
        assert w in str(e.value)


def test_bytes_do_not_depend_on_workers_and_an_item_regenerates_alone(photos, tmp_path):
    img, dep = photos
    opts = dict(input=img, depth=dep, variants=3, seed=2, rain_rate_mm_h="5:80", wind_m_s="-4:4", f_number="2:11", parquet=True, progress=False)
    one = dataset.generate(out=tmp_path / "one", **opts)
    two = dataset.generate(out=tmp_path / "two", workers=2, **opts)
    assert one.generated == two.generated == 6 and one.errors == two.errors == 12  # c.png needs depth_scale_m
    a = tree(tmp_path / "one")
    assert a == tree(tmp_path / "two")
    # the parquet manifest holds the JSON rows' values
    import pyarrow.parquet as pq

    table = pq.read_table(tmp_path / "one" / "manifest.parquet").to_pylist()
    rows = dataset.read_manifest(tmp_path / "one")
    assert [t["index"] for t in table] == [r["index"] for r in rows] == list(range(18))
    for t, r in zip(table, rows):
        assert t["status"] == r["status"] and t.get("error") == r.get("error")
        if r["status"] == "ok":
            assert dict(t["files"]) == r["files"]
            assert t["params.rain_rate_mm_h"] == r["params"]["rain_rate_mm_h"] and t["params.f_number"] == r["params"]["f_number"]
            assert t["params.visibility_m"] == math.inf
    alone = dataset.generate(out=tmp_path / "alone", indices=[4], **opts)
    assert alone.generated == 1
    b = tree(tmp_path / "alone")
    assert {k for k in b if k.startswith("items/")} == {k for k in a if k.startswith("items/000004.")}
    assert all(b[k] == a[k] for k in b if k.startswith("items/"))
    row = json.loads(b["items/000004.json"])
    assert row["image"] == "b.png" and row["status"] == "ok" and row["depth"] == "b.npy"


def test_resume_regenerates_only_what_is_missing_or_corrupt(tmp_path):
    opts = dict(out=tmp_path / "ds", scene="street", variants=5, width=W, height=H, ambient_spacing_m=8.0, progress=False)
    s = dataset.generate(**opts)
    assert 0.0 < s.first_to_last_s < s.seconds and s.steady_items_per_s == pytest.approx(4 / s.first_to_last_s)
    assert s.items_per_s == pytest.approx(5 / s.seconds)
    before = tree(tmp_path / "ds")
    items = tmp_path / "ds" / "items"
    data = bytearray((items / "000001.rain.png").read_bytes())
    data[-20] ^= 0xFF
    (items / "000001.rain.png").write_bytes(bytes(data))
    (items / "000003.rain_alpha.npy").unlink()
    (items / "000004.json").write_text("{trunc")
    s = dataset.generate(resume=True, **opts)
    assert (s.generated, s.skipped) == (3, 2)
    assert tree(tmp_path / "ds") == before
    # other options: every item is made again
    s = dataset.generate(resume=True, **{**opts, "seed": 1})
    assert (s.generated, s.skipped) == (5, 0)


def test_the_far_level_of_detail_draws_a_dataset_and_keeps_the_old_checksum(tmp_path):
    opts = dict(scene="street", variants=2, width=W, height=H, ambient_spacing_m=8.0, progress=False, rain_rate_mm_h="20:40")
    plain = DatasetConfig(out="x", scene="street")
    assert DatasetConfig(out="x", scene="street", rain_far_m=None).sha256() == plain.sha256()
    assert DatasetConfig(out="x", scene="street", rain_far_m=2.0).sha256() != plain.sha256()
    a = dataset.generate(out=tmp_path / "far", rain_far_m=2.0, **opts)
    b = dataset.generate(out=tmp_path / "near", **opts)
    assert a.generated == b.generated == 2
    fa = np.load(tmp_path / "far" / "items" / "000000.rain_alpha.npy")
    fb = np.load(tmp_path / "near" / "items" / "000000.rain_alpha.npy")
    assert fa.mean() > 0 and not np.array_equal(fa, fb)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "skyfall.cli", "dataset", *args]


def _rows(items: Path) -> int:
    """Manifest rows under their final names in ``items``."""
    return sum(1 for p in items.glob("*.json") if not p.name.startswith(".")) if items.is_dir() else 0


def _kill_when(cmd: list[str], items: Path, rows: int) -> None:
    """Start ``cmd``, ``kill -9`` it once ``items`` holds ``rows`` manifest rows and a file is being written."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and _rows(items) < rows and proc.poll() is None:
        time.sleep(0.002)
    # then at the first temporary file seen: mid-write
    while time.monotonic() < deadline and proc.poll() is None and not any(p.name.startswith(".") for p in items.iterdir()):
        pass
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run ended before it was killed: the test proves nothing"


def test_kill_9_then_resume_gives_the_bytes_of_an_uninterrupted_run(tmp_path):
    # zlib level 9 makes writing a large share of each item, so kills land mid-write too
    args = ["--scene", "street", "--width", "160", "--height", "90", "--variants", "40", "--seed", "4",
            "--ambient-spacing-m", "8", "--visibility-m", "200:2000", "--layers", "rain_alpha,transmittance,rain_depth_m",
            "--png-compression", "9", "--no-progress"]
    ref, run = tmp_path / "ref", tmp_path / "run"
    subprocess.run(_cli(*args, "--out", str(ref)), check=True, capture_output=True)
    ref_files = tree(ref)
    # killed once, resumed and killed again, then resumed to the end
    for cmd, rows in ((_cli(*args, "--out", str(run)), 5), (_cli(*args, "--out", str(run), "--resume"), 15)):
        _kill_when(cmd, run / "items", rows)
        assert not (run / "manifest.jsonl").exists()
        done = tree(run)
        # nothing half-written under a final name: every final file is the uninterrupted run's
        for name, data in done.items():
            if not Path(name).name.startswith("."):
                assert data == ref_files[name], name
        print(f"killed with {_rows(run / 'items')} rows; "
              f"temporaries left: {[k for k in done if Path(k).name.startswith('.')]}")
    rows_done = _rows(run / "items")
    assert 15 <= rows_done < 40
    out = subprocess.run(_cli(*args, "--out", str(run), "--resume"), check=True, capture_output=True, text=True).stdout
    assert f"{40 - rows_done} generated, {rows_done} kept" in out, out
    final = tree(run)
    assert final == ref_files
    assert not any(Path(k).name.startswith(".") for k in final)


def test_the_command_line_and_its_config_file(photos, tmp_path, capsys):
    from skyfall import cli

    for argv in ([], ["dataset"], ["render"]):
        with pytest.raises(SystemExit) as e:
            cli.main([*argv, "--help"])
        assert e.value.code == 0
    text = capsys.readouterr().out
    for option in ("--rain-rate", "--visibility-m", "--exposure-s", "--f-number", "--workers", "--resume", "--config", "--png-compression"):
        assert option in text
    # --layers' help names every layer an item can write (the core's list)
    from skyfall import _core

    layers_help = re.sub(r"\s+", " ", text.rsplit("--layers NAMES", 1)[1].split(" --", 1)[0])
    for name in _core.LAYERS:
        assert name in layers_help, name
    common = ["--scene", "street", "--width", str(W), "--height", str(H), "--variants", "3", "--ambient-spacing-m", "8", "--no-progress"]
    assert cli.main(["dataset", *common, "--rain-rate", "3:30", "--seed", "8", "--out", str(tmp_path / "a")]) == 0
    toml = tmp_path / "run.toml"
    toml.write_text(f'[dataset]\nscene = "street"\nwidth = {W}\nheight = {H}\nvariants = 3\nambient-spacing-m = 8.0\n'
                    f'rain_rate = "3:30"\nseed = 8\nout = "{tmp_path / "b"}"\nprogress = false\n')
    assert cli.main(["dataset", "--config", str(toml)]) == 0
    assert tree(tmp_path / "a") == tree(tmp_path / "b")
    assert cli.main(["dataset", *common, "--rain-rate", "3:900", "--out", str(tmp_path / "c")]) == 2
    assert "rain_rate_mm_h" in capsys.readouterr().err
    toml.write_text("rain_rat = 3\n")
    assert cli.main(["dataset", "--config", str(toml)]) == 2
    assert "unknown option 'rain_rat'" in capsys.readouterr().err
    img, dep = photos
    exr = tmp_path / "photo.exr"
    assert cli.main(["render", "--input", str(img / "a.png"), "--depth", str(dep / "a.exr"), "--rain-rate", "40", "--visibility-m", "500", "--out", str(exr)]) == 0
    channels = io.read_channels(exr)
    assert channels["rain_alpha"].max() > 0 and channels["transmittance"].max() < 1
    np.testing.assert_array_equal(channels["depth_m"], io.read_channels(dep / "a.exr")["depth_m"])
    assert cli.main(["render", "--input", str(tmp_path / "missing.png"), "--out", str(tmp_path / "x.png")]) == 1
    assert "missing.png" in capsys.readouterr().err
    png, alpha = tmp_path / "one.png", tmp_path / "alpha.npy"
    assert cli.main(["render", "--width", str(W), "--height", str(H), "--rain-rate", "30", "--exposure-s", "0.002",
                     "--seed", "3", "--out", str(png), "--alpha-out", str(alpha)]) == 0
    # the same frame from a TOML file's [render] table
    toml.write_text(f'[render]\nwidth = {W}\nheight = {H}\nrain-rate = 30.0\nexposure_s = 0.002\nseed = 3\nout = "{tmp_path / "two.png"}"\n'
                    '[dataset]\nvariants = 9\n')
    assert cli.main(["render", "--config", str(toml)]) == 0
    assert (tmp_path / "two.png").read_bytes() == png.read_bytes()
    # the same frame through the API
    from skyfall import Camera, Weather

    street = scenes.street()
    c = street.camera
    cam = Camera(tuple(c.position_m), yaw_deg=c.yaw_deg, pitch_deg=c.pitch_deg, vertical_fov_deg=c.vertical_fov_deg, exposure_s=0.002)
    frame = Renderer(W, H, backend="cpu").render(street, Weather(rain_rate_mm_h=30.0), camera=cam, seed=3)
    np.testing.assert_array_equal(np.load(alpha), frame.layers["rain_alpha"])
    np.testing.assert_array_equal(io.read_image(png), io.decode_srgb8(io.to_srgb8(frame.rgb)))


def test_the_console_script_is_installed():
    exe = Path(sys.executable).parent / "skyfall"
    out = subprocess.run([str(exe), "--help"], check=True, capture_output=True, text=True).stdout
    assert "dataset" in out and "render" in out and "demo" in out


def test_ctrl_c_stops_the_workers_cleanly_and_resume_finishes(tmp_path):
    run = tmp_path / "run"
    args = ["--scene", "street", "--width", "160", "--height", "90", "--variants", "60", "--ambient-spacing-m", "8",
            "--png-compression", "9", "--workers", "2", "--no-progress", "--out", str(run)]
    # a child of a background job inherits SIGINT ignored; Python then keeps ignoring it
    proc = subprocess.Popen(
        _cli(*args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and _rows(run / "items") < 4 and proc.poll() is None:
        time.sleep(0.005)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, f"exit {proc.returncode}, {_rows(run / 'items')} rows\nstdout: {stdout}\nstderr: {stderr}"
    assert "interrupted" in stdout and "Traceback" not in stderr
    assert not any(p.name.startswith(".") for p in (run / "items").iterdir())  # the items in flight finished
    assert not (run / "manifest.jsonl").exists()
    s = dataset.generate(out=run, scene="street", width=160, height=90, variants=60, ambient_spacing_m=8.0, png_compression=9, resume=True, progress=False)
    assert s.skipped >= 4 and s.generated + s.skipped == 60 and s.errors == 0
    rows = dataset.read_manifest(run)
    assert [r["status"] for r in rows] == ["ok"] * 60
    check_checksums(run, rows)


@pytest.fixture
def environ_restored():
    """os.environ as it was before the test: a Dask LocalCluster leaves MALLOC_TRIM_THRESHOLD_,
    PYTHONHASHSEED and OMP_NUM_THREADS set in this process, and later tests' worker processes
    inherit them."""
    saved = dict(os.environ)
    yield
    os.environ.clear()
    os.environ.update(saved)


def test_a_dask_local_cluster_writes_the_bytes_of_a_local_run(photos, tmp_path, environ_restored):
    from dask.distributed import Client, LocalCluster

    img, dep = photos
    opts = dict(input=img, depth=dep, variants=2, seed=11, rain_rate_mm_h="5:60", visibility_m="300:3000",
                layers=("rain_alpha", "transmittance"), progress=False)
    local = dataset.generate(out=tmp_path / "local", **opts)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None) as cluster, Client(cluster) as client:
        s = dataset.generate(out=tmp_path / "dask", scheduler=client, **opts)
        assert (s.generated, s.errors) == (local.generated, local.errors) == (4, 8)  # c.png needs depth_scale_m
        assert tree(tmp_path / "dask") == tree(tmp_path / "local")
        # by address, and resumed: nothing left to do
        s = dataset.generate(out=tmp_path / "dask", scheduler=cluster.scheduler_address, resume=True, **opts)
        assert (s.generated, s.skipped, s.errors) == (0, 4, 8)  # the error items are tried again
    assert tree(tmp_path / "dask") == tree(tmp_path / "local")


def _worker_pids(parent: int) -> list[int]:
    """The parent's multiprocessing workers (not its resource tracker), from /proc."""
    pids = []
    for task in Path(f"/proc/{parent}/task").iterdir():
        children = task / "children"
        if children.exists():
            pids += [int(p) for p in children.read_text().split()]
    return [p for p in pids if b"resource_tracker" not in Path(f"/proc/{p}/cmdline").read_bytes()]


def test_a_worker_killed_with_kill_9_stops_the_run_and_resume_finishes(tmp_path):
    run = tmp_path / "run"
    args = ["--scene", "street", "--width", "160", "--height", "90", "--variants", "60", "--ambient-spacing-m", "8",
            "--png-compression", "9", "--workers", "2", "--no-progress", "--out", str(run)]
    proc = subprocess.Popen(_cli(*args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and _rows(run / "items") < 4 and proc.poll() is None:
        time.sleep(0.005)
    workers = _worker_pids(proc.pid)
    assert len(workers) == 2, workers
    os.kill(workers[0], signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 1, f"exit {proc.returncode}\nstdout: {stdout}\nstderr: {stderr}"
    assert "a worker process died" in stderr and "--resume" in stderr and "Traceback" not in stderr
    s = dataset.generate(out=run, scene="street", width=160, height=90, variants=60, ambient_spacing_m=8.0, png_compression=9, resume=True, progress=False)
    assert s.skipped >= 4 and s.generated + s.skipped == 60 and s.errors == 0
    rows = dataset.read_manifest(run)
    assert [r["status"] for r in rows] == ["ok"] * 60
    check_checksums(run, rows)


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d.name))
    found: set[int] = set()
    stack = [pid]
    while stack:
        for c in children.get(stack.pop(), []):
            found.add(c)
            stack.append(c)
    return found


def _alive(pid: int) -> bool:
    """Running (a zombie, dead but not reaped by a container's init, is not)."""
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(sys.platform != "linux", reason="/proc is Linux's")
def test_kill_9_of_a_run_with_workers_ends_the_workers_and_the_resource_tracker(tmp_path):
    args = ["--scene", "street", "--width", "160", "--height", "90", "--variants", "400", "--ambient-spacing-m", "8",
            "--workers", "2", "--no-progress", "--out", str(tmp_path / "run")]
    proc = subprocess.Popen(_cli(*args), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and _rows(tmp_path / "run" / "items") < 2 and proc.poll() is None:
            time.sleep(0.02)
        below = _descendants(proc.pid)
        assert proc.poll() is None and len(below) >= 3, f"no run with two workers to kill: {below}"  # 2 workers + the tracker
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    # the workers end with their parent (a parent-death signal), then the tracker (its pipe closes)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and any(_alive(p) for p in below):
        time.sleep(0.05)
    left = [p for p in below if _alive(p)]
    for p in left:  # leave nothing behind, then fail
        os.kill(p, signal.SIGKILL)
    assert not left, f"{len(left)} of {len(below)} processes outlived their parent's kill -9"


@pytest.mark.parametrize("workers", ["1", "2"])
def test_an_interrupted_run_counts_what_it_finished_and_writes_no_config(tmp_path, workers):
    out = tmp_path / "run"
    args = ["--scene", "street", "--width", "160", "--height", "90", "--variants", "120", "--ambient-spacing-m", "8",
            "--workers", workers, "--no-progress", "--out", str(out)]
    proc = subprocess.Popen(_cli(*args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300  # (a loaded machine starts slowly)
    while time.monotonic() < deadline and _rows(out / "items") < 3 and proc.poll() is None:
        time.sleep(0.01)
    if _rows(out / "items") < 3:
        proc.kill()
        pytest.fail(f"the run wrote no 3 rows to interrupt (exit {proc.wait()})")
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr[-2000:]
    m = re.search(r"^interrupted: 120 items: (\d+) generated, 0 kept, (\d+) errors", stdout, re.M)
    assert m, stdout
    rows = [json.loads(p.read_text()) for p in (out / "items").glob("*.json")]
    assert int(m.group(1)) == sum(r["status"] == "ok" for r in rows) >= 3
    assert int(m.group(2)) == sum(r["status"] != "ok" for r in rows)
    # config.json and the manifest are written once the run is complete
    assert not (out / "config.json").exists() and not (out / "manifest.jsonl").exists()
    done = subprocess.run(_cli(*args, "--resume"), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (out / "config.json").exists() and (out / "manifest.jsonl").exists()
