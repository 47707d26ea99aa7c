"""The dataset's pipeline inside a worker (an item encoded and written while the next renders)
and its encoding options: the same bytes as items made one at a time, errors of the writing
stage recorded per item, an interrupt that leaves every written item complete."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from skyfall import io
from skyfall.dataset import generate
from skyfall.dataset.run import _chunks
from skyfall.dataset.item import ItemSource, Worker, render_item, render_items, verify_item
from skyfall.dataset.sample import DatasetConfig

from test_dataset import tree

SMALL = {"scene": "street", "width": 48, "height": 32, "ambient_spacing_m": 8.0}


def config(out: Path, **kw: object) -> DatasetConfig:
    return DatasetConfig(out=out, **{"variants": 4, "seed": 3, **SMALL, **kw})  # type: ignore[arg-type]


def test_pipelined_items_are_the_bytes_of_items_made_one_at_a_time(tmp_path):
    a, b = config(tmp_path / "a"), config(tmp_path / "b")
    for c in (a, b):
        (c.out / "items").mkdir(parents=True)
    srcs = [ItemSource(i) for i in range(4)]
    rows = [row for row, _ in render_items(Worker(a), srcs)]
    assert [r["index"] for r in rows] == [0, 1, 2, 3] and all(r["status"] == "ok" for r in rows)
    wb = Worker(b)
    for s in srcs:
        render_item(wb, s)
    assert tree(a.out) == tree(b.out)


def test_an_error_while_writing_is_the_items_and_the_run_goes_on(tmp_path):
    cfg = config(tmp_path / "run")
    (cfg.out / "items").mkdir(parents=True)
    (cfg.out / "items" / "000001.rain.png").mkdir()  # the rename onto it fails
    s = generate(cfg, progress=False)
    assert (s.generated, s.errors) == (3, 1)
    assert "item 1:" in s.error_messages[0]
    assert [verify_item(cfg, i) for i in range(4)] == [True, False, True, True]


def test_an_interrupt_while_rendering_finishes_the_item_being_written(tmp_path):
    cfg = config(tmp_path / "run")
    (cfg.out / "items").mkdir(parents=True)

    def sources() -> Iterator[ItemSource]:
        yield ItemSource(0)
        yield ItemSource(1)
        raise KeyboardInterrupt  # as Ctrl-C would, while item 1 is being written

    got = []
    with pytest.raises(KeyboardInterrupt):
        for row, _ in render_items(Worker(cfg), sources()):
            got.append(row["index"])
    assert got == [0]  # item 1's row was not handed out, but its files and row are complete
    assert verify_item(cfg, 0) and verify_item(cfg, 1)
    assert not any(p.name.startswith(".") for p in (cfg.out / "items").iterdir())


def test_chunks_cover_every_item_once_and_feed_every_worker():
    todo = [ItemSource(i) for i in range(10)]
    for workers in (1, 2, 3, 8):
        chunks = _chunks(todo, workers)
        assert [s.index for c in chunks for s in c] == list(range(10))
        assert max(len(c) for c in chunks) <= 4
        assert len(chunks) >= min(10, 2 * workers) or max(len(c) for c in chunks) == 1


@pytest.mark.parametrize("compression", ["none", "piz", "zips"])
def test_exr_compressions_are_lossless_and_zip_is_the_default(tmp_path, compression):
    runs = {}
    for name in ("zip", compression):
        cfg = config(tmp_path / name, variants=1, exr=True, exr_compression=name)
        assert generate(cfg, progress=False).errors == 0
        runs[name] = cfg.out / "items" / "000000.rain.exr"
    a, b = (io.read_channels(runs[n]) for n in ("zip", compression))
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])
    if compression == "none":
        assert runs["none"].stat().st_size > runs["zip"].stat().st_size
    # "zip" is what the frame writes without being told (and the config checksum of before)
    plain = tmp_path / "plain.exr"
    from skyfall import Renderer, scenes

    Renderer(48, 32).render(scenes.street(), ambient_spacing_m=8.0).save(plain)
    import OpenImageIO as oiio

    spec = oiio.ImageInput.open(str(plain)).spec()
    assert spec.get_string_attribute("compression") == "zip"
    assert config(tmp_path, exr_compression="zip").sha256() == config(tmp_path).sha256()
    assert config(tmp_path, exr_compression=compression).sha256() != config(tmp_path).sha256()


def test_a_bad_exr_compression_names_the_choices(tmp_path):
    with pytest.raises(ValueError, match="exr_compression = 'lzw' must be one of zip, zips, piz, rle, none"):
        config(tmp_path, exr_compression="lzw")


def test_a_yaml_config_is_the_toml_one(tmp_path, capsys):
    from skyfall import cli

    body = {"scene": "street", "width": 48, "height": 32, "variants": 2, "ambient-spacing-m": 8.0, "rain_rate": "3:30", "seed": 8, "progress": False}
    toml = tmp_path / "run.toml"
    toml.write_text("[dataset]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"').replace("False", "false") for k, v in body.items()) + f'out = "{tmp_path / "t"}"\n')
    yml = tmp_path / "run.yaml"
    yml.write_text("dataset:\n" + "".join(f"  {k}: {v!r}\n".replace("False", "false") for k, v in body.items()) + f"  out: {tmp_path / 'y'}\n")
    assert cli.main(["dataset", "--config", str(toml)]) == 0
    assert cli.main(["dataset", "--config", str(yml)]) == 0
    assert tree(tmp_path / "t") == tree(tmp_path / "y")
    yml.write_text("- a list\n- not options\n")
    assert cli.main(["dataset", "--config", str(yml)]) == 2
    assert "a YAML config is a mapping" in capsys.readouterr().err
    yml.write_text("rain_rate: [unclosed\n")
    assert cli.main(["dataset", "--config", str(yml)]) == 2
    assert "not valid YAML" in capsys.readouterr().err


def test_png_strategies_keep_the_pixels(tmp_path):
    made = {}
    for strategy in ("huffman", "default", "rle"):
        cfg = config(tmp_path / strategy, variants=1, png_strategy=strategy, rain_rate_mm_h="40:40")
        assert generate(cfg, progress=False).errors == 0
        made[strategy] = cfg.out / "items" / "000000.rain.png"
    pixels = {k: io.read_stored(p)[0] for k, p in made.items()}
    np.testing.assert_array_equal(pixels["huffman"], pixels["default"])
    np.testing.assert_array_equal(pixels["rle"], pixels["default"])
    assert made["huffman"].read_bytes() != made["default"].read_bytes()  # the strategy was applied
    # the clean image is written with zlib's default strategy whatever the option
    assert (tmp_path / "huffman/items/000000.clean.png").read_bytes() == (tmp_path / "default/items/000000.clean.png").read_bytes()
    with pytest.raises(ValueError, match="png_strategy = 'fast' must be one of huffman, default, rle, filtered"):
        config(tmp_path, png_strategy="fast")


def test_a_snow_range_is_drawn_last_and_moves_no_other_parameter(tmp_path):
    from dataclasses import replace

    from skyfall.dataset.sample import sample_item

    rain = config(tmp_path, rain_rate_mm_h="1:50", wind_m_s="-5:5")
    both = config(tmp_path, rain_rate_mm_h="1:50", wind_m_s="-5:5", snow_rate_mm_h="0.5:4")
    for i in range(6):
        a, b = sample_item(rain, i), sample_item(both, i)
        assert a.snow_rate_mm_h == 0.0 and 0.5 <= b.snow_rate_mm_h <= 4.0
        assert replace(b, snow_rate_mm_h=0.0) == a
    assert rain.sha256() == config(tmp_path, rain_rate_mm_h="1:50", wind_m_s="-5:5", snow_rate_mm_h=0).sha256()
    assert both.sha256() != rain.sha256()
    with pytest.raises(ValueError, match="snow_rate_mm_h"):
        config(tmp_path, snow_rate_mm_h="1:500")


def test_snow_with_its_cover_and_a_windshield_give_their_layers(tmp_path):
    cfg = config(tmp_path / "snowy", variants=2, rain_rate_mm_h=0, snow_rate_mm_h="1:3", snow_hours="0.5:1", snow_resolution_m=2.0,
                 wind_m_s="-1:1", layers=("snow_alpha", "snow_depth_m", "rain_alpha"))
    s = generate(cfg, progress=False)
    assert (s.generated, s.errors) == (2, 0), s.error_messages
    for i in range(2):
        stem = cfg.out / "items" / f"{i:06d}"
        assert np.load(f"{stem}.snow_alpha.npy").max() > 0.0   # flakes
        assert np.load(f"{stem}.snow_depth_m.npy").max() > 0.001  # lying snow, m
        assert np.load(f"{stem}.rain_alpha.npy").max() == 0.0   # no rain: the neutral layer
    rows = [r for r in (json.loads((cfg.out / "items" / f"{i:06d}.json").read_text()) for i in range(2))]
    for r in rows:
        assert 0.5 <= r["params"]["snow_hours"] <= 1.0 and r["snow_cover"]["mean_depth_m"] > 0.0
        # an hour at R mm/h of water lays about R cm at 100 kg/m^3 on open ground; less under the
        # buildings' shelter, none on walls
        assert r["snow_cover"]["mean_depth_m"] < 0.01 * r["params"]["snow_rate_mm_h"] * r["params"]["snow_hours"] * 1.5
    # the same items again, one alone: the same bytes (the cover is seeded by the item)
    alone = config(tmp_path / "alone", variants=2, rain_rate_mm_h=0, snow_rate_mm_h="1:3", snow_hours="0.5:1", snow_resolution_m=2.0,
                   wind_m_s="-1:1", layers=("snow_alpha", "snow_depth_m", "rain_alpha"))
    generate(alone, progress=False, indices=[1])
    for name in rows[1]["files"]:
        assert (alone.out / "items" / name).read_bytes() == (cfg.out / "items" / name).read_bytes(), name
    with pytest.raises(ValueError, match="snow_hours needs snow_rate_mm_h"):
        config(tmp_path, snow_hours="1:2")
    with pytest.raises(ValueError, match=r"snow_hours = 3000 is outside the valid range \[0, 2778\] h"):
        config(tmp_path, snow_rate_mm_h=1, snow_hours=3000)


def test_a_windshield_preset_per_item(tmp_path):
    cfg = config(tmp_path / "glass", variants=2, rain_rate_mm_h="5:10", windshield="drizzle", layers=("drop_mask", "drop_height"))
    s = generate(cfg, progress=False)
    assert (s.generated, s.errors) == (2, 0), s.error_messages
    masks = [np.load(cfg.out / "items" / f"{i:06d}.drop_mask.npy") for i in range(2)]
    assert all(m.max() > 0.0 for m in masks) and not np.array_equal(masks[0], masks[1])  # drops, a time each
    with pytest.raises(ValueError, match="windshield = 'hail' must be one of"):
        config(tmp_path, windshield="hail")


def test_clouds_in_every_items_sky(tmp_path):
    cfg = config(tmp_path / "clouds", variants=2, rain_rate_mm_h="0:2", clouds="cumulus", layers=("cloud_alpha", "rain_alpha"))
    s = generate(cfg, progress=False)
    assert (s.generated, s.errors) == (2, 0), s.error_messages
    alphas = [np.load(cfg.out / "items" / f"{i:06d}.cloud_alpha.npy") for i in range(2)]
    assert all(a.max() > 0.3 for a in alphas)  # the cumulus 5 km down the street, above its end
    # the same items without clouds: the same checksum as before the option, no cloud layer
    plain = config(tmp_path / "plain", variants=2, rain_rate_mm_h="0:2", layers=("rain_alpha",))
    assert plain.sha256() != cfg.sha256()
    assert "clouds" not in json.dumps(plain.to_json()) or plain.to_json()["clouds"] is None
    with pytest.raises(ValueError, match="clouds = 'nimbus' must be one of"):
        config(tmp_path, clouds="nimbus")


def test_wet_street_items_carry_their_wetness(tmp_path):
    # 2-10 mm/h for 30-60 s: the open ground's film is R t / 3600 mm, its wetness that over
    # 0.2 mm (the layer's maximum, on the open road); walls stay dry in a calm.
    cfg = config(tmp_path / "wet", variants=3, rain_rate_mm_h="2:10", rain_duration_s="30:60", layers=("wetness",))
    s = generate(cfg, progress=False)
    assert (s.generated, s.errors) == (3, 0), s.error_messages
    for i in range(3):
        row = json.loads((cfg.out / "items" / f"{i:06d}.json").read_text())
        p = row["params"]
        wet = np.load(cfg.out / "items" / f"{i:06d}.wetness.npy")
        want = min(1.0, p["rain_rate_mm_h"] * p["rain_duration_s"] / 3600.0 / 0.2)
        assert 30.0 <= p["rain_duration_s"] <= 60.0
        np.testing.assert_allclose(wet.max(), want, rtol=1e-5)
        assert (wet == 0.0).any()
    with pytest.raises(ValueError, match="rain_duration_s"):
        config(tmp_path, rain_duration_s="-1:5")
