"""The ``skyfall`` command: ``skyfall dataset``, ``skyfall render`` and ``skyfall demo``.

Every option of ``dataset`` and ``render`` can also come from a TOML file (``--config
run.toml``) or a YAML one (``run.yaml``, ``.yml``, through PyYAML's safe loader): its keys are the options' long names, with ``-`` or ``_`` (``rain-rate = "1:50"``,
``variants = 100``, ``layers = ["rain_alpha", "transmittance"]``), at the top level or in a
``[dataset]`` / ``[render]`` table (a ``dataset:`` / ``render:`` mapping in YAML); options given on the command line win over the file's.
Relative paths in the file are taken from the current folder, as on the command line.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import tomllib
from pathlib import Path
from typing import Any

__all__ = ["main"]

EXIT_OK, EXIT_IO, EXIT_USAGE, EXIT_ITEM_ERRORS, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

# option (dest) -> (flags, help). Each dest is a DatasetConfig field or a generate() keyword.
_DATASET_OPTIONS: list[tuple[str, tuple[str, ...], dict[str, Any]]] = [
    ("input", ("--input",), {"type": Path, "metavar": "DIR", "help": "folder of photos (any format OpenImageIO reads), in name order"}),
    ("scene", ("--scene",), {"choices": ["street"], "help": "the bundled street, its camera jittered per item (instead of --input)"}),
    ("depth", ("--depth",), {"metavar": "DIR|estimate", "help": "depth maps matched to the photos by stem (.exr metres with inf = sky, .npy, .pfm, 16-bit .png with --depth-scale-m; see --depth-format); a photo without one is an error for its item. 'estimate': a monocular network (pip install 'skyfall[depth]'). Without --depth: the sky estimated, everything else at --distance-m (the ground plane with --camera-height-m or --horizon-row)"}),
    ("depth_format", ("--depth-format",), {"choices": ["kitti", "cityscapes", "middlebury", "exr", "npy", "scaled"], "help": "the depth maps' format (cityscapes: camera file STEM.json beside each map; middlebury: STEM.txt or calib.txt); default from the suffix"}),
    ("depth_model", ("--depth-model",), {"metavar": "NAME|FILE", "help": "--depth estimate: the network, depth-anything-v2-small (default, downloaded once) or an ONNX file"}),
    ("depth_scale_m", ("--depth-scale-m",), {"type": float, "metavar": "M", "help": "metres per unit of integer depth (16-bit PNG, integer NPY), e.g. 0.001 for mm; refused with float depth"}),
    ("distance_m", ("--distance-m",), {"type": float, "metavar": "M", "help": "without depth maps: the distance of everything that is not sky, m, in (0, 1e5]; default 10 (with --depth estimate: the median distance)"}),
    ("out", ("--out",), {"type": Path, "metavar": "DIR", "help": "output folder (items/, manifest.jsonl, config.json)"}),
    ("variants", ("--variants",), {"type": int, "metavar": "N", "help": "items per photo (per scene), default 1"}),
    ("seed", ("--seed",), {"type": int, "metavar": "S", "help": "master seed, in [0, 2^63); item i's parameters come from (seed, i) alone; default 0"}),
    ("width", ("--width",), {"type": int, "metavar": "PX", "help": "frame width of --scene items, default 640 (photos keep their size)"}),
    ("height", ("--height",), {"type": int, "metavar": "PX", "help": "frame height of --scene items, default 360"}),
    ("rain_rate_mm_h", ("--rain-rate", "--rain-rate-mm-h"), {"metavar": "LO:HI", "help": "rain rate, mm/h, in [0, 500], sampled uniformly; default 1:50"}),
    ("visibility_m", ("--visibility-m",), {"metavar": "LO:HI", "help": "visibility of the air without rain, m, log-uniform; default inf (clear air)"}),
    ("exposure_s", ("--exposure-s",), {"metavar": "LO:HI", "help": "shutter time, s, in [1e-6, 0.1], log-uniform; default 0.004:0.0333"}),
    ("f_number", ("--f-number",), {"metavar": "LO:HI", "help": "f-number, in [0.5, 256], log-uniform; default none (a pinhole)"}),
    ("focus_distance_m", ("--focus-distance-m",), {"metavar": "LO:HI", "help": "focus distance, m, log-uniform (needs --f-number); default inf"}),
    ("wind_m_s", ("--wind-m-s",), {"metavar": "LO:HI", "help": "cross wind (x), m/s, in [-60, 60], uniform; default 0"}),
    ("snow_rate_mm_h", ("--snow-rate", "--snow-rate-mm-h"), {"metavar": "LO:HI", "help": "snowfall rate as liquid-water equivalent, mm/h, in [0, 100], uniform; default 0 (no snow)"}),
    ("snow_hours", ("--snow-hours",), {"metavar": "LO:HI", "help": "hours the snow has lain, in [0, 2777], uniform: each item's snow cover (needs --snow-rate); default 0 (no cover)"}),
    ("rain_duration_s", ("--rain-duration-s",), {"metavar": "LO:HI", "help": "how long the rain has fallen on the surfaces, s, in [0, 1e7], uniform: wet, darker, mirroring roads with puddles (writes wetness and puddle_mask when asked); default 0 (dry)"}),
    ("snow_resolution_m", ("--snow-resolution-m",), {"type": float, "metavar": "M", "help": "cell side of the snow cover, m, in [0.01, 100]; default 0.25"}),
    ("clouds", ("--clouds",), {"metavar": "PRESET", "help": "clouds in every item's sky: broken, cumulus or stratocumulus (skyfall.clouds.PRESETS); writes cloud_alpha when asked"}),
    ("windshield", ("--windshield",), {"nargs": "?", "const": "rain", "metavar": "PRESET", "help": "see each item through a windshield with wipers: drizzle, rain (the default with no PRESET), downpour or parked; writes drop_mask and drop_height when asked"}),
    ("rain_near_m", ("--rain-near-m",), {"type": float, "metavar": "M", "help": "radius of the streak region, m, in (0, 50]; default 5"}),
    ("rain_far_m", ("--rain-far-m",), {"type": float, "metavar": "M", "help": "draw the drops beyond M m (horizontally, below --rain-near-m) as pre-rasterised layers: faster in heavy rain and deep regions (CPU backend, no --f-number); default every drop one by one"}),
    ("camera_height_m", ("--camera-height-m",), {"type": float, "metavar": "M", "help": "photos without depth maps show a level ground plane: the camera's height, m (default 1.6 with --horizon-row)"}),
    ("horizon_row", ("--horizon-row",), {"type": float, "metavar": "ROW", "help": "photos without depth maps show a level ground plane: the horizon's row, px from the top (default the middle with --camera-height-m)"}),
    ("vertical_fov_deg", ("--vertical-fov-deg",), {"type": float, "metavar": "DEG", "help": "the photos' vertical field of view, degrees; default each photo's EXIF 35 mm focal length's, else 60"}),
    ("camera_jitter_m", ("--camera-jitter-m",), {"type": float, "metavar": "M", "help": "--scene: camera moves within +-M in x and z; default 0.5"}),
    ("camera_jitter_deg", ("--camera-jitter-deg",), {"type": float, "metavar": "DEG", "help": "--scene: camera turns within +-DEG in yaw (half in pitch); default 5"}),
    ("layers", ("--layers",), {"metavar": "NAMES", "help": "ground-truth layers to write as float32 .npy, comma separated, of rain_alpha, rain_depth_m, transmittance, snow_alpha, snow_depth_m, drop_mask, drop_height, cloud_alpha, sun_transmittance, wetness, puddle_mask (or 'none'); default rain_alpha (the fast 8-bit path; other layers render float frames)"}),
    ("exr", ("--exr",), {"action": "store_const", "const": True, "help": "also write each weather frame as EXR (float RGB, depth and layers)"}),
    ("exr_compression", ("--exr-compression",), {"choices": ["zip", "zips", "piz", "rle", "none"], "help": "--exr: the EXR's lossless compression; default zip (none: fastest, largest)"}),
    ("png_strategy", ("--png-strategy",), {"choices": ["huffman", "default", "rle", "filtered"], "help": "zlib strategy of the weather PNGs; default huffman (on rainy photos faster than zlib's default and no larger)"}),
    ("png_compression", ("--png-compression",), {"type": int, "metavar": "0-9", "help": "PNG zlib level (png:compressionLevel); default 1, fast: at 1080p level 6 takes 300-500 ms a PNG"}),
    ("ambient_spacing_m", ("--ambient-spacing-m",), {"type": float, "metavar": "M", "help": "--scene: ambient-light map spacing, m; default 1 (coarser is faster)"}),
    ("backend", ("--backend",), {"choices": ["cpu", "gpu", "auto"], "help": "renderer backend; default cpu (the same bytes on every machine)"}),
    ("parquet", ("--parquet",), {"action": "store_const", "const": True, "help": "also write manifest.parquet (pip install 'skyfall[parquet]')"}),
    ("sequence", ("--sequence",), {"type": int, "metavar": "N", "help": "each item a clip of N frames, in [1, 10000] (rain falling at time k/fps): NNNNNN.rain.mp4, .clean.mp4 and each layer as an (N, H, W) .npy stack (pip install 'skyfall[video]')"}),
    ("fps", ("--fps",), {"type": float, "metavar": "F", "help": "--sequence: frames per second, in (0, 1000]; default 30"}),
    ("video_lossless", ("--video-lossless",), {"action": "store_const", "const": True, "help": "--sequence: lossless clips (x264 RGB: every byte of the frames); default lossy crf 18, even sizes only"}),
]
_RUN_OPTIONS: list[tuple[str, tuple[str, ...], dict[str, Any]]] = [
    ("workers", ("--workers",), {"type": int, "metavar": "K", "help": "worker processes, each with one renderer; default 1 (in this process)"}),
    ("scheduler", ("--scheduler",), {"metavar": "tcp://HOST:PORT", "help": "render on a Dask distributed cluster instead (pip install 'skyfall[dask]'); --out and the inputs must be on a file system every worker sees"}),
    ("threads_per_worker", ("--threads-per-worker",), {"type": int, "metavar": "T", "help": "renderer threads per worker; default the cores shared out"}),
    ("resume", ("--resume",), {"action": "store_const", "const": True, "help": "keep the items already complete (files present, checksums intact) and generate the rest"}),
    ("items", ("--items",), {"metavar": "I,J,...", "help": "only these item indices (e.g. one regenerated alone); the manifest is left as it is"}),
    ("progress", ("--no-progress",), {"action": "store_const", "const": False, "help": "no progress bar"}),
]
_RENDER_OPTIONS: list[tuple[str, tuple[str, ...], dict[str, Any]]] = [
    ("input", ("--input",), {"type": Path, "metavar": "FILE", "help": "a photo (instead of --scene)"}),
    ("scene", ("--scene",), {"choices": ["street"], "help": "the bundled street (default when no --input)"}),
    ("depth", ("--depth",), {"metavar": "FILE|estimate", "help": "the photo's depth map (.exr, .npy, .pfm, 16-bit .png; see --depth-format) or 'estimate' (pip install 'skyfall[depth]'); without one, the sky estimated and the rest at --distance-m"}),
    ("depth_format", ("--depth-format",), {"choices": ["kitti", "cityscapes", "middlebury", "exr", "npy", "scaled"], "help": "the depth map's format; default from the suffix"}),
    ("depth_scale_m", ("--depth-scale-m",), {"type": float, "metavar": "M", "help": "metres per unit of integer depth"}),
    ("distance_m", ("--distance-m",), {"type": float, "metavar": "M", "help": "without a depth map: the distance of everything that is not sky, m; default 10"}),
    ("out", ("--out",), {"type": Path, "metavar": "FILE", "help": "output image: .png (8-bit sRGB) or .exr (float RGB, depth_m and the layers)"}),
    ("width", ("--width",), {"type": int, "metavar": "PX", "help": "street frame width, default 640"}),
    ("height", ("--height",), {"type": int, "metavar": "PX", "help": "street frame height, default 360"}),
    ("rain_rate_mm_h", ("--rain-rate", "--rain-rate-mm-h"), {"type": float, "metavar": "MM_H", "help": "rain rate, mm/h, in [0, 500]; default 10"}),
    ("visibility_m", ("--visibility-m",), {"type": float, "metavar": "M", "help": "visibility of the air without rain, m; default inf"}),
    ("exposure_s", ("--exposure-s",), {"type": float, "metavar": "S", "help": "shutter time, s, in [1e-6, 0.1]; default 1/30"}),
    ("f_number", ("--f-number",), {"type": float, "metavar": "N", "help": "f-number (a thin lens); default a pinhole"}),
    ("focus_distance_m", ("--focus-distance-m",), {"type": float, "metavar": "M", "help": "focus distance, m (needs --f-number); default inf"}),
    ("wind_m_s", ("--wind-m-s",), {"type": float, "metavar": "M_S", "help": "cross wind (x), m/s, in [-60, 60]; default 0"}),
    ("rain_near_m", ("--rain-near-m",), {"type": float, "metavar": "M", "help": "radius of the streak region, m; default 5"}),
    ("rain_far_m", ("--rain-far-m",), {"type": float, "metavar": "M", "help": "drops beyond M m (horizontally) as pre-rasterised layers (CPU backend, no --f-number); default none"}),
    ("seed", ("--seed",), {"type": int, "metavar": "S", "help": "the rain's seed; default 0"}),
    ("camera_height_m", ("--camera-height-m",), {"type": float, "metavar": "M", "help": "a level ground plane: the camera's height, m (default 1.6 with --horizon-row)"}),
    ("horizon_row", ("--horizon-row",), {"type": float, "metavar": "ROW", "help": "a level ground plane: the horizon's row, px (default the middle with --camera-height-m)"}),
    ("vertical_fov_deg", ("--vertical-fov-deg",), {"type": float, "metavar": "DEG", "help": "the photo's vertical field of view; default its EXIF focal length's, else 60"}),
    ("backend", ("--backend",), {"choices": ["cpu", "gpu", "auto"], "help": "renderer backend; default cpu"}),
]
_ALIASES = {"rain_rate": "rain_rate_mm_h", "snow_rate": "snow_rate_mm_h"}


def _add(parser: argparse.ArgumentParser, options: list[tuple[str, tuple[str, ...], dict[str, Any]]]) -> None:
    for dest, flags, kw in options:
        parser.add_argument(*flags, dest=dest, default=None, **kw)


def _parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(
        prog="skyfall",
        description="Physically grounded weather for images: datasets, single frames and the demo.",
        epilog="Run 'skyfall COMMAND --help' for a command's options.",
    )
    from skyfall import __version__

    top.add_argument("--version", action="version", version=f"skyfall {__version__}")
    sub = top.add_subparsers(dest="command", metavar="COMMAND", required=True)
    ds = sub.add_parser(
        "dataset",
        help="turn a folder of photos (or the street) into weather variants with ground truth",
        description=(
            "Render VARIANTS weather variants of every photo in --input (or of --scene street) into --out: per item "
            "items/NNNNNN.rain.png (the weather image), .clean.png, one float32 .npy per --layers (with --sequence N: "
            "clips .rain.mp4 and .clean.mp4 of N frames and (N, H, W) .npy stacks), and a manifest row "
            "items/NNNNNN.json (every sampled parameter, the seed, the version, each file's sha256), gathered into "
            "manifest.jsonl at the end. Ranges LO:HI are sampled per item from (seed, item index) alone: the bytes do "
            "not depend on --workers, and --resume after an interruption (Ctrl-C, kill -9) gives the bytes of an "
            "uninterrupted run. Exit status: 0; 1 for a file that cannot be read or written or a worker process killed; 2 for invalid options; 3 when "
            "some items failed (each recorded in its manifest row); 130 when interrupted."
        ),
        epilog="Example: skyfall dataset --input photos --out wet --variants 10 --rain-rate 1:50 --visibility-m 300:5000 --workers 2",
    )
    ds.add_argument("--config", type=Path, metavar="FILE", help="read options from a TOML file, or YAML (.yaml, .yml) (command-line options win)")
    _add(ds, _DATASET_OPTIONS)
    _add(ds, _RUN_OPTIONS)
    rd = sub.add_parser(
        "render",
        help="render one frame of the street or of a photo",
        description=(
            "Render one frame: --scene street (default) or a photo (--input, optional --depth), written to --out. "
            "Exit status: 0; 1 for a file that cannot be read or written; 2 for invalid options."
        ),
        epilog="Example: skyfall render --scene street --rain-rate 25 --wind-m-s 3 --out street.png",
    )
    rd.add_argument("--config", type=Path, metavar="FILE", help="read options from a TOML file, or YAML (.yaml, .yml) (command-line options win)")
    rd.add_argument("--alpha-out", type=Path, metavar="FILE", default=None, help="also write the rain_alpha layer (.npy float32, or .png 8-bit)")
    _add(rd, _RENDER_OPTIONS)
    dm = sub.add_parser("demo", help="render the demo outputs (what make demo runs)", description="Render the demo outputs into --out (python -m skyfall._demo).")
    dm.add_argument("--out", default="out", help="output folder (created); default out")
    return top


def _read_config(path: Path) -> dict[str, Any]:
    """The file's mapping: YAML for ``.yaml``/``.yml`` (PyYAML's safe loader), else TOML."""
    try:
        text = path.read_text()
    except OSError as e:
        raise ValueError(f"--config {path}: {e.strerror or e}") from None
    if path.suffix.lower() in (".yaml", ".yml"):
        try:
            import yaml
        except ImportError:
            raise ValueError(f"--config {path}: YAML needs PyYAML (pip install 'skyfall[dataset]'), or use TOML") from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as e:
            raise ValueError(f"--config {path}: not valid YAML ({e})") from None
        if data is None:
            return {}
        if not isinstance(data, dict):
            raise ValueError(f"--config {path}: a YAML config is a mapping of option: value, got a {type(data).__name__}")
        return data
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"--config {path}: not valid TOML ({e})") from None


def _load_config(path: Path, table: str, allowed: set[str]) -> dict[str, Any]:
    data = _read_config(path)
    if isinstance(data.get(table), dict):
        data = {**{k: v for k, v in data.items() if not isinstance(v, dict)}, **data[table]}
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            continue  # another command's table
        name = _ALIASES.get(key.replace("-", "_"), key.replace("-", "_"))
        if name not in allowed:
            raise ValueError(f"--config {path}: unknown option {key!r} (options: {', '.join(sorted(allowed))})")
        out[name] = value
    return out


def _merge(args: argparse.Namespace, options: list[tuple[str, tuple[str, ...], dict[str, Any]]], table: str) -> dict[str, Any]:
    dests = {d for d, _, _ in options}
    merged = _load_config(args.config, table, dests) if args.config is not None else {}
    for d in dests:
        v = getattr(args, d)
        if v is not None:
            merged[d] = v
    return merged


def _dataset(args: argparse.Namespace) -> int:
    from skyfall import dataset

    opts = _merge(args, _DATASET_OPTIONS + _RUN_OPTIONS, "dataset")
    run = {k: opts.pop(k) for k in ("workers", "threads_per_worker", "resume", "items", "progress", "scheduler") if k in opts}
    if isinstance(opts.get("layers"), str):
        text = opts["layers"].strip()
        opts["layers"] = () if text in ("", "none") else tuple(s.strip() for s in text.split(","))
    if "out" not in opts:
        raise ValueError("--out is required (the output folder)")
    items = run.pop("items", None)
    indices: list[int] | None = None
    if items is not None:
        try:
            indices = [int(s) for s in str(items).split(",")] if not isinstance(items, list) else [int(s) for s in items]
        except ValueError:
            raise ValueError(f"--items = {items!r} must be item indices separated by commas") from None
    config = dataset.DatasetConfig(**opts)
    summary = dataset.generate(config, indices=indices, **run)
    print(summary)
    for message in summary.error_messages[:20]:
        print("  " + message, file=sys.stderr)
    if summary.interrupted:
        print("interrupted: run again with --resume to finish", file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_ITEM_ERRORS if summary.errors else EXIT_OK


def _render(args: argparse.Namespace) -> int:
    from skyfall import io
    from skyfall.dataset.item import ItemSource, Worker, prepare
    from skyfall.dataset.sample import DatasetConfig, ItemParams

    opts = _merge(args, _RENDER_OPTIONS, "render")
    if "out" not in opts:
        raise ValueError("--out is required (the output image, .png or .exr)")
    out = Path(opts.pop("out"))
    image = opts.pop("input", None)
    depth = opts.pop("depth", None)
    seed = opts.pop("seed", 0)
    if image is None:
        opts.setdefault("scene", "street")
    elif opts.get("scene") is not None:
        raise ValueError("give --input (a photo) or --scene, not both")
    scalars = {k: opts.pop(k) for k in ("rain_rate_mm_h", "visibility_m", "exposure_s", "f_number", "focus_distance_m", "wind_m_s") if k in opts}
    scalars.setdefault("rain_rate_mm_h", 10.0)
    scalars.setdefault("exposure_s", 1.0 / 30.0)
    ranges: dict[str, Any] = {k: (v, v) for k, v in scalars.items()}
    folder = Path(image).parent if image is not None else None
    estimate = depth == "estimate"
    config = DatasetConfig(
        out=out.parent,
        input=folder,
        depth="estimate" if estimate else None if depth is None else Path(depth).parent,
        camera_jitter_m=0.0,
        camera_jitter_deg=0.0,
        **ranges,
        **opts,
    )
    f_number = None if config.f_number is None else config.f_number[0]
    focus = (config.focus_distance_m[0] if config.focus_distance_m is not None else math.inf) if f_number is not None else None
    p = ItemParams(
        index=0,
        render_seed=int(seed),
        rain_rate_mm_h=config.rain_rate_mm_h[0],
        visibility_m=config.visibility_m[0],
        exposure_s=config.exposure_s[0],
        f_number=f_number,
        focus_distance_m=focus,
        wind_m_s=config.wind_m_s[0],
        camera_dx_m=0.0,
        camera_dz_m=0.0,
        camera_dyaw_deg=0.0,
        camera_dpitch_deg=0.0,
    )
    if not 0 <= p.render_seed < 2**64:
        raise ValueError(f"seed = {p.render_seed} is outside the valid range [0, 2^64)")
    worker = Worker(config)
    src = ItemSource(0, None if image is None else Path(image), None if depth is None or estimate else Path(depth))
    row: dict[str, Any] = {}
    scene, camera, weather = prepare(worker, src, p, row)
    renderer = worker.renderer(int(row["width"]), int(row["height"]))
    frame = renderer.render(scene, weather, camera=camera, seed=p.render_seed, ambient_spacing_m=config.ambient_spacing_m)
    out.parent.mkdir(parents=True, exist_ok=True)
    frame.save(out)
    alpha_out: Path | None = args.alpha_out
    if alpha_out is not None:
        alpha = frame.layers.get("rain_alpha")
        import numpy as np

        a = alpha if alpha is not None else np.zeros(frame.depth_m.shape, np.float32)
        if alpha_out.suffix.lower() == ".npy":
            np.save(alpha_out, a)
        else:
            io.write_image(alpha_out, a, encoding="linear")
    print(f"wrote {out} ({row['width']}x{row['height']}, {weather.rain_rate_mm_h:g} mm/h, {frame.stats.get('rain_streaks', 0)} streaks)")
    return EXIT_OK


# A value that starts with "-" but is a number or a range: "-5:5", "-1e3", "-inf", "-.5:-0.1".
_NEGATIVE = re.compile(r"^-(\d|\.\d|inf\b|infinity\b)", re.IGNORECASE)


def _join_negative_values(argv: list[str]) -> list[str]:
    """``--wind-m-s -5:5`` as ``--wind-m-s=-5:5``: argparse takes a value that starts with
    ``-`` for an option unless it is a plain negative number (``-5``), so a negative range
    (``-5:5``) or ``-1e3`` would fail with "expected one argument"."""
    takes_value = {
        flag
        for dest, flags, kw in _DATASET_OPTIONS + _RUN_OPTIONS + _RENDER_OPTIONS
        if "action" not in kw and "nargs" not in kw
        for flag in flags
    }
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--":
            out.extend(argv[i:])
            break
        if a in takes_value and i + 1 < len(argv) and _NEGATIVE.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the ``skyfall`` command; returns its exit status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).
    """
    parser = _parser()
    args = parser.parse_args(_join_negative_values(list(sys.argv[1:] if argv is None else argv)))
    if args.command == "demo":
        from skyfall import _demo as demo

        return demo.main(["--out", str(args.out)])
    try:
        return _dataset(args) if args.command == "dataset" else _render(args)
    except (ValueError, TypeError, FileNotFoundError) as e:
        print(f"skyfall {args.command}: error: {e}", file=sys.stderr)
        return EXIT_USAGE
    except (OSError, RuntimeError) as e:  # a file that cannot be read or written, a worker killed
        print(f"skyfall {args.command}: error: {e}", file=sys.stderr)
        return EXIT_IO
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
