"""A dataset run's options and the per-item sampling of its parameter ranges.

Every item's parameters come from ``numpy.random.SeedSequence([seed, index])`` alone, drawn in
a fixed order, so any item can be regenerated on its own and a run's results do not depend on
the number of workers or the order in which items finish.
"""

from __future__ import annotations

import hashlib
import json
import math
import numbers
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from skyfall import _core
from skyfall._validate import in_range, integer, real
from skyfall.weather import Weather

__all__ = ["DatasetConfig", "EXR_COMPRESSIONS", "PNG_STRATEGIES", "ItemParams", "parse_range", "sample_item", "LAYER_NAMES", "RANGE_OPTIONS"]

_FIRST_LAYERS = ("rain_alpha", "rain_depth_m", "transmittance", "snow_alpha", "snow_depth_m", "drop_mask", "drop_height", "cloud_alpha")
LAYER_NAMES = (*_FIRST_LAYERS, *(n for n in _core.LAYERS if n not in _FIRST_LAYERS))
"""Every layer an item can write (the core's ``_core.LAYERS``), the first eight in the order
items have listed their files in since before the list was the core's."""
"""The ground-truth layers an item can write (``layers=``)."""

# option -> (the parameter whose valid range its ends must lie in, how it is sampled)
RANGE_OPTIONS: dict[str, tuple[str, str]] = {
    "rain_rate_mm_h": ("rain_rate_mm_h", "uniform"),
    "visibility_m": ("visibility_m", "log"),
    "exposure_s": ("exposure_s", "log"),
    "f_number": ("f_number", "log"),
    "focus_distance_m": ("focus_distance_m", "log"),
    "wind_m_s": ("wind_m_s", "uniform"),
    "snow_rate_mm_h": ("snow_rate_mm_h", "uniform"),
}

Range = tuple[float, float]


def parse_range(name: str, value: Any, *, check: bool = True) -> Range:
    """A parameter range ``(lo, hi)`` from ``"1:50"``, ``"10"``, a number or a pair.

    Parameters
    ----------
    name : str
        The option's name (``rain_rate_mm_h``, ...), whose valid range both ends must lie in.
    value : str, float or sequence of 2 float
        ``"lo:hi"`` or ``[lo, hi]`` samples in [lo, hi]; one number is a fixed value.
    check : bool
        Check both ends against the parameter's valid range (False: the caller checks them).

    Raises
    ------
    ValueError
        When the text is not a number or ``lo:hi``, ``lo > hi``, or an end is outside the
        parameter's valid range (the message names the parameter and its range).
    TypeError
        For a value that is neither text, a number nor a pair.
    """
    ends: list[Any]
    if isinstance(value, str):
        parts = value.split(":")
        if len(parts) not in (1, 2):
            raise ValueError(f"{name} = {value!r} must be a number or a range lo:hi")
        try:
            ends = [float(p) for p in parts]
        except ValueError:
            raise ValueError(f"{name} = {value!r} must be a number or a range lo:hi of numbers") from None
    elif isinstance(value, numbers.Real) and not isinstance(value, bool):
        ends = [float(value)]
    elif isinstance(value, (list, tuple)) and len(value) in (1, 2):
        ends = list(value)
    else:
        raise TypeError(f"{name} must be a number, a range 'lo:hi' or a pair [lo, hi], got {value!r}")
    param = RANGE_OPTIONS[name][0] if name in RANGE_OPTIONS else name
    checked = [in_range(param, e) for e in ends] if check else [float(e) for e in ends]
    lo, hi = checked[0], checked[-1]
    if lo > hi:
        raise ValueError(f"{name} = {lo:g}:{hi:g} is empty: lo must be at most hi")
    if RANGE_OPTIONS.get(name, ("", "uniform"))[1] == "log" and math.isinf(lo) != math.isinf(hi):
        raise ValueError(f"{name} = {lo:g}:{hi:g}: a log-uniform range must be finite at both ends, or a fixed inf")
    return (lo, hi)


HOURS_MAX = 1e7 / 3600.0
"""The longest cover, h: ``skyfall.snow.accumulate``'s ``duration_s`` of 1e7 s."""


def _hours(value: Any) -> Range:
    """``snow_hours``: a range of hours in [0, :data:`HOURS_MAX`]."""
    lo, hi = parse_range("snow_hours", value, check=False)
    for v in (lo, hi):
        if not 0.0 <= v <= HOURS_MAX:
            raise ValueError(f"snow_hours = {v:g} is outside the valid range [0, {HOURS_MAX:.0f}] h")
    return (lo, hi)


def _optional_range(name: str, value: Any) -> Range | None:
    return None if value is None else parse_range(name, value)


PNG_STRATEGIES = ("huffman", "default", "rle", "filtered")
"""zlib's strategies a dataset's weather PNGs are written with (``DatasetConfig.png_strategy``)."""

EXR_COMPRESSIONS = ("zip", "zips", "piz", "rle", "none")
"""The lossless EXR compressions a dataset writes with (``DatasetConfig.exr_compression``)."""

@dataclass(frozen=True)
class DatasetConfig:
    """The options of a dataset run (:func:`skyfall.dataset.generate` and ``skyfall dataset``).

    Parameters
    ----------
    out : Path
        Output folder (created).
    input : Path, optional
        Folder of photos (any format OpenImageIO reads: PNG, JPEG, TIFF, EXR, ...), taken in
        name order. Exactly one of ``input`` and ``scene`` is given.
    depth : Path or "estimate", optional
        Folder of depth maps matched to the photos by file stem, read by
        :func:`skyfall.io.read_depth` in ``depth_format`` (default from the suffix: ``.exr``
        metres, ``.npy``, ``.pfm`` Middlebury, 16-bit ``.png``/``.tif`` with ``depth_scale_m``);
        a photo without its depth map is an error for that item. ``"estimate"``: depth from a
        monocular network (:func:`skyfall.depth.estimate`, the ``skyfall[depth]`` extra) with
        ``depth_model``. Without ``depth``: the photo scene model
        (:class:`skyfall.PhotoScene`): the estimated sky, everything else at ``distance_m``,
        and the ground plane only with ``camera_height_m`` or ``horizon_row``.
    depth_format : str, optional
        One of :data:`skyfall.io.DEPTH_FORMATS` for every depth map (``"kitti"``,
        ``"cityscapes"`` with its camera file ``STEM.json`` beside the map, ``"middlebury"``
        with ``STEM.txt`` or ``calib.txt`` beside it, ``"exr"``, ``"npy"``, ``"scaled"``).
    depth_model : str, optional
        With ``depth="estimate"``: a name in :data:`skyfall.depth.MODELS` or an ONNX file
        (default ``"depth-anything-v2-small"``).
    distance_m : float, optional
        Without a depth file: the distance of what is not sky, m (default 10; with
        ``depth="estimate"`` the median distance it is calibrated to).
    scene : {"street"}, optional
        The bundled street (:func:`skyfall.scenes.street`) with its camera jittered per item.
    variants : int
        Items per photo (per scene for ``scene``), in [1, 10^7].
    seed : int
        The master seed, in [0, 2^63).
    width, height : int
        Frame size of ``scene`` items, px (photos keep their own size).
    rain_rate_mm_h, visibility_m, exposure_s, f_number, focus_distance_m, wind_m_s : (lo, hi)
        Ranges sampled per item (see :func:`parse_range`); rain rate and wind (the x
        component, m/s, across the view) uniform, visibility, exposure, f-number and focus
        distance log-uniform. ``f_number`` None: a pinhole; ``focus_distance_m`` None: focused at
        infinity.
    snow_rate_mm_h : (lo, hi)
        Snowfall rate as liquid-water equivalent, mm/h, in [0, 100], uniform (default 0: no
        snow); rain and snow may fall together.
    snow_hours : (lo, hi)
        How long the snow has been lying, h, uniform in [0, 2777] (default 0: no cover): each
        item's cover is :func:`skyfall.snow.accumulate` of its own snow rate and wind over
        that time (``snow_resolution_m`` cells, 300 s steps, the item's seed), drawn with the
        frame (``snow_depth_m``). Needs ``snow_rate_mm_h``.
    rain_duration_s : (lo, hi)
        How long the rain has fallen on the surfaces, s, in [0, 1e7], uniform (default 0: dry
        surfaces): each item's ``Weather.rain_duration_s``, so its surfaces darken and mirror
        (the README's "Wet surfaces"), with the ``wetness`` layer when asked. 10 mm/h for
        72 s fill the 0.2 mm film that reads fully wet.
    snow_resolution_m : float
        The cover's cell side, m, in [0.01, 100] (default 0.25: about a second per item for
        an hour of snow on the street).
    windshield : str, optional
        A :data:`skyfall.windshield.PRESETS` name: each item seen through a windshield in that
        rain (its own glass rate, wipers and car speed), at a time drawn per item in
        [0, 60) s from one warm state per worker (:func:`skyfall.windshield.warm`, the run's
        seed: the preset's steady glass drawn in about 0.1 s; a worker's first items step it
        to the starts of the later periods of its 4-period epoch once, about a second a period
        for ``rain`` on 2 cores, and each item at most a period from there), with the
        ``drop_mask`` and ``drop_height`` layers.
    clouds : str, optional
        A :data:`skyfall.clouds.PRESETS` name: clouds in every item's sky (over a photo's sky
        pixels, before the haze), lit by the overcast sky's light, with the ``cloud_alpha``
        layer when asked. The preset's volumes are built once per worker.
    rain_near_m : float
        Radius of the streak region, m (:class:`skyfall.Weather`).
    rain_far_m : float, optional
        The rain's far level of detail (:class:`skyfall.Weather`): drops beyond this
        horizontal distance, m, drawn as layers; below ``rain_near_m``, CPU backend and
        pinhole cameras only. None (default): every drop one by one.
    depth_scale_m : float, optional
        Metres per unit of integer depth maps (16-bit PNG, integer NPY).
    camera_height_m, horizon_row : float, optional
        Either asks for the ground plane (photos without a depth file): the camera's height
        (default 1.6 m) and the horizon's row (default the middle).
    vertical_fov_deg : float, optional
        The photos' vertical field of view, degrees; default each photo's EXIF 35 mm
        focal length's, else 60.
    camera_jitter_m, camera_jitter_deg : float
        ``scene`` items: the camera moves uniformly within +-jitter_m in x and z and turns
        within +-jitter_deg in yaw (+-jitter_deg / 2 in pitch).
    layers : tuple of str
        Ground-truth layers to write, each of :data:`LAYER_NAMES`, as float32 ``.npy``.
        ``("rain_alpha",)`` on an 8-bit photo keeps the fast fused 8-bit path
        (:meth:`skyfall.Renderer.render_srgb8`); any other layer, ``exr`` or a ``scene`` item
        renders the float frame (:meth:`skyfall.Renderer.render`) and encodes it.
    exr : bool
        Also write the weather frame as EXR (float RGB and the layers).
    exr_compression : str
        The EXR's compression, one of :data:`EXR_COMPRESSIONS` (all lossless; OpenEXR's
        ``compression`` attribute): ``"zip"`` (default, OpenImageIO's), ``"zips"`` (per
        scanline), ``"piz"`` (wavelet, often smaller for noisy float data), ``"rle"``,
        ``"none"`` (the fastest to write, the largest).
    png_compression : int
        zlib level of the PNGs, in [0, 9] (OpenImageIO's ``png:compressionLevel``; the filter is
        libpng's SUB). Default 1, for speed: a 1080p photo takes 27 ms to write at 1 and 89 ms
        at 6 (137 ms at 6 with libpng's default filters, OpenImageIO's default; noisier rainy
        photos about twice as long), against 24-46 ms to render; 0 stores them uncompressed
        (6.2 MB at 1080p, 14 ms). See benches/results/dataset.md.
    png_strategy : str
        zlib's strategy for the weather images' PNGs, one of :data:`PNG_STRATEGIES`
        (OpenImageIO's PNG ``compression`` attribute): ``"huffman"`` (default: Huffman codes
        only, no string matching: on rainy 1080p photos at level 1, 25-35 % faster than
        zlib's default strategy and no larger, since the rain's noise leaves few matches),
        ``"default"``, ``"rle"``, ``"filtered"``. The clean images (smooth, and a photo's
        encoded once) always use zlib's default.
    ambient_spacing_m : float
        Ambient-light map spacing of ``scene`` items, m (each item's rain changes the sky, so
        its map is built again: about 0.3 s at 1 m for the street).
    backend : {"cpu", "gpu", "auto"}
        The renderer's backend. "cpu" (default) gives the same bytes on every machine.
    parquet : bool
        Also write the manifest as ``manifest.parquet`` (pyarrow: ``pip install
        "skyfall[parquet]"``), nested parameters as dotted columns.
    sequence : int, optional
        Frames per item, in [1, 10^4]: each item becomes a clip (``NNNNNN.rain.mp4`` and
        ``NNNNNN.clean.mp4`` through :func:`skyfall.video.write_video`, and each layer as one
        float32 ``.npy`` stack of shape (N, H, W)); frame k is rendered at ``time_s = k / fps``
        with the item's seed, so its world-anchored rain falls over the static photo or street.
        None (default): one still per item (PNG). Needs PyAV (``pip install "skyfall[video]"``).
    fps : float
        Frames per second of a clip, in (0, 1000]; default 30. Only with ``sequence``.
    video_lossless : bool
        Write the clips losslessly (x264 RGB, quality 0: every decoded byte is the frame
        rendered, about ten times larger); default lossy 4:2:0 at crf 18, which needs an even
        width and height. Only with ``sequence``. Lossless clips, the layer stacks and the
        rows are the same bytes on any number of workers and after a resume; lossy clips
        encode the same frames but x264's bytes can differ between processes (see
        :mod:`skyfall.video`).
    """

    out: Path
    input: Path | None = None
    depth: Path | str | None = None
    scene: str | None = None
    variants: int = 1
    seed: int = 0
    width: int = 640
    height: int = 360
    rain_rate_mm_h: Range = (1.0, 50.0)
    visibility_m: Range = (math.inf, math.inf)
    exposure_s: Range = (1.0 / 250.0, 1.0 / 30.0)
    f_number: Range | None = None
    focus_distance_m: Range | None = None
    wind_m_s: Range = (0.0, 0.0)
    snow_rate_mm_h: Range = (0.0, 0.0)
    snow_hours: Range = (0.0, 0.0)
    rain_duration_s: Range = (0.0, 0.0)
    snow_resolution_m: float = 0.25
    windshield: str | None = None
    clouds: str | None = None
    rain_near_m: float = 5.0
    rain_far_m: float | None = None
    depth_scale_m: float | None = None
    depth_format: str | None = None
    depth_model: str | None = None
    distance_m: float | None = None
    camera_height_m: float | None = None
    horizon_row: float | None = None
    vertical_fov_deg: float | None = None
    camera_jitter_m: float = 0.5
    camera_jitter_deg: float = 5.0
    layers: tuple[str, ...] = ("rain_alpha",)
    exr: bool = False
    exr_compression: str = "zip"
    png_compression: int = 1
    png_strategy: str = "huffman"
    ambient_spacing_m: float = 1.0
    backend: str = "cpu"
    parquet: bool = False
    sequence: int | None = None
    fps: float = 30.0
    video_lossless: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "out", Path(self.out))
        if (self.input is None) == (self.scene is None):
            raise ValueError("give exactly one of input (a folder of photos) and scene ('street')")
        if self.scene is not None and self.scene != "street":
            raise ValueError(f"scene = {self.scene!r} must be 'street'")
        if self.depth is not None and self.input is None:
            raise ValueError("depth needs input: depth maps are matched to the input photos by stem")
        set_(self, "input", None if self.input is None else Path(self.input))
        if self.depth is not None and not isinstance(self.depth, (str, Path)):
            raise TypeError(f"depth must be a folder (str or Path) or 'estimate', got {type(self.depth).__name__}")
        set_(self, "depth", self.depth if self.depth is None or self.depth == "estimate" else Path(self.depth))
        for name in ("depth_format", "depth_model"):
            if getattr(self, name) is not None and not isinstance(getattr(self, name), str):
                raise TypeError(f"{name} must be a name (str), got {type(getattr(self, name)).__name__}")
        if self.depth_format is not None:
            from skyfall.io import DEPTH_FORMATS

            if self.depth_format not in DEPTH_FORMATS:
                raise ValueError(f"depth_format = {self.depth_format!r} must be one of {', '.join(DEPTH_FORMATS)}")
            if not isinstance(self.depth, Path):
                raise ValueError("depth_format needs depth, a folder of depth maps")
        if self.depth_model is not None and self.depth != "estimate":
            raise ValueError("depth_model needs depth='estimate'")
        if self.distance_m is not None:
            if isinstance(self.depth, Path):
                raise ValueError("distance_m is the depth assumed without depth maps; depth gives them")
            set_(self, "distance_m", in_range("distance_m", self.distance_m))
        for name in ("windshield", "clouds", "png_strategy", "exr_compression", "backend"):  # names, not values
            v = getattr(self, name)
            if not (isinstance(v, str) or (v is None and name in ("windshield", "clouds"))):
                raise TypeError(f"{name} must be a name (str), got {type(v).__name__}")
        set_(self, "variants", integer("variants", self.variants, 1, 10**7))
        set_(self, "seed", integer("seed", self.seed, 0, 2**63 - 1))
        set_(self, "width", integer("width", self.width, 1, 16384))
        set_(self, "height", integer("height", self.height, 1, 16384))
        for name in ("rain_rate_mm_h", "visibility_m", "exposure_s", "wind_m_s", "snow_rate_mm_h", "rain_duration_s"):
            set_(self, name, parse_range(name, getattr(self, name)))
        set_(self, "f_number", _optional_range("f_number", self.f_number))
        set_(self, "focus_distance_m", _optional_range("focus_distance_m", self.focus_distance_m))
        if self.focus_distance_m is not None and self.f_number is None:
            raise ValueError("focus_distance_m needs f_number (a pinhole is in focus at every distance)")
        set_(self, "rain_near_m", in_range("rain_near_m", self.rain_near_m))
        if self.rain_far_m is not None:
            set_(self, "rain_far_m", in_range("rain_far_m", self.rain_far_m))
            Weather(rain_near_m=self.rain_near_m, rain_far_m=self.rain_far_m)  # the core's check: rain_far_m below rain_near_m
            if self.f_number is not None:
                raise ValueError("rain_far_m draws its layers in focus: it cannot be used with f_number (a thin lens)")
        set_(self, "snow_hours", _hours(self.snow_hours))
        if self.snow_hours[1] > 0.0 and self.snow_rate_mm_h[1] <= 0.0:
            raise ValueError("snow_hours needs snow_rate_mm_h (a cover is the snow that fell)")
        try:  # the range of snow.accumulate's resolution_m, under this option's own name
            set_(self, "snow_resolution_m", in_range("resolution_m", self.snow_resolution_m))
        except (TypeError, ValueError) as e:
            raise type(e)("snow_resolution_m" + str(e).removeprefix("resolution_m")) from None
        if self.windshield is not None:
            from skyfall.windshield import PRESETS

            if self.windshield not in PRESETS:
                raise ValueError(f"windshield = {self.windshield!r} must be one of {', '.join(PRESETS)}")
        if self.clouds is not None:
            from skyfall.clouds import PRESETS as CLOUDS

            if self.clouds not in CLOUDS:
                raise ValueError(f"clouds = {self.clouds!r} must be one of {', '.join(CLOUDS)}")
        if self.depth_scale_m is not None:
            s = float(self.depth_scale_m)
            if not (math.isfinite(s) and s > 0.0):
                raise ValueError(f"depth_scale_m = {self.depth_scale_m} must be a positive finite number of metres per unit")
            set_(self, "depth_scale_m", s)
        if self.camera_height_m is not None:
            set_(self, "camera_height_m", in_range("camera_height_m", self.camera_height_m))
        if self.horizon_row is not None:
            set_(self, "horizon_row", in_range("horizon_row", self.horizon_row))
        if (self.camera_height_m is not None or self.horizon_row is not None) and isinstance(self.depth, Path):
            raise ValueError("camera_height_m and horizon_row ask for the ground plane, used without depth maps; depth gives them")
        if self.vertical_fov_deg is not None:
            set_(self, "vertical_fov_deg", in_range("vertical_fov_deg", self.vertical_fov_deg))
        for name, hi in (("camera_jitter_m", 100.0), ("camera_jitter_deg", 45.0)):
            v = real(name, getattr(self, name))
            if not 0.0 <= v <= hi:
                raise ValueError(f"{name} = {v:g} is outside the valid range [0, {hi:g}]")
            set_(self, name, v)
        if not isinstance(self.layers, (str, tuple, list)):
            raise TypeError(f"layers must be a name or a sequence of names, got {type(self.layers).__name__}")
        layers = (self.layers,) if isinstance(self.layers, str) else tuple(self.layers)
        for name in layers:
            if name not in LAYER_NAMES:
                raise ValueError(f"layers: {name!r} is not one of {', '.join(LAYER_NAMES)}")
        set_(self, "layers", tuple(n for n in LAYER_NAMES if n in layers))
        for name in ("exr", "parquet", "video_lossless"):
            if not isinstance(getattr(self, name), bool):
                raise TypeError(f"{name} must be True or False, got {getattr(self, name)!r}")
        set_(self, "png_compression", integer("png_compression", self.png_compression, 0, 9))
        if self.png_strategy not in PNG_STRATEGIES:
            raise ValueError(f"png_strategy = {self.png_strategy!r} must be one of {', '.join(PNG_STRATEGIES)}")
        if self.exr_compression not in EXR_COMPRESSIONS:
            raise ValueError(f"exr_compression = {self.exr_compression!r} must be one of {', '.join(EXR_COMPRESSIONS)}")
        set_(self, "ambient_spacing_m", in_range("ambient_spacing_m", self.ambient_spacing_m))
        if self.backend not in ("cpu", "gpu", "auto"):
            raise ValueError(f"backend = {self.backend!r} must be 'cpu', 'gpu' or 'auto'")
        if self.sequence is not None:
            set_(self, "sequence", integer("sequence", self.sequence, 1, 10**4))
            if self.exr:
                raise ValueError("exr is for stills: with sequence the clips are MP4 and the layers .npy stacks")
        fps = real("fps", self.fps)
        if not 0.0 < fps <= 1000.0:
            raise ValueError(f"fps = {fps:g} is outside the valid range (0, 1000]")
        set_(self, "fps", fps)
        if self.sequence is None and (self.fps != 30.0 or self.video_lossless):
            raise ValueError("fps and video_lossless need sequence (the frames per clip)")

    def to_json(self) -> dict[str, Any]:
        """The options as JSON values (paths as text, ranges as pairs, inf as the string "inf")."""
        d = asdict(self)
        return {k: _jsonable(v) for k, v in d.items()}

    def sha256(self) -> str:
        """A checksum of the options that shape the items (not ``out``): a resumed run
        regenerates every item when they changed."""
        d = self.to_json()
        d.pop("out")
        if self.sequence is None:  # stills: the checksum of the options before clips existed
            for name in ("sequence", "fps", "video_lossless"):
                d.pop(name)
        if d["exr_compression"] == "zip":  # the checksum of the options before it was one
            d.pop("exr_compression")
        for name, plain in (("snow_rate_mm_h", [0.0, 0.0]), ("snow_hours", [0.0, 0.0]), ("rain_duration_s", [0.0, 0.0]), ("snow_resolution_m", 0.25), ("windshield", None), ("clouds", None), ("rain_far_m", None),
                            ("depth_format", None), ("depth_model", None), ("distance_m", None)):
            if d[name] == plain:  # not used: the checksum of before it was an option
                d.pop(name)
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()

    @classmethod
    def option_names(cls) -> list[str]:
        """The names of the options, as ``generate`` and a config file take them."""
        return [f.name for f in fields(cls)]


def _jsonable(v: Any) -> Any:
    if isinstance(v, Path):
        return str(v)
    if isinstance(v, float) and not math.isfinite(v):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, (tuple, list)):
        return [_jsonable(x) for x in v]
    return v


@dataclass(frozen=True)
class ItemParams:
    """One item's sampled parameters (units in the names; None: not used)."""

    index: int
    render_seed: int
    rain_rate_mm_h: float
    visibility_m: float
    exposure_s: float
    f_number: float | None
    focus_distance_m: float | None
    wind_m_s: float
    camera_dx_m: float
    camera_dz_m: float
    camera_dyaw_deg: float
    camera_dpitch_deg: float
    snow_rate_mm_h: float = 0.0
    snow_hours: float = 0.0
    windshield_time_s: float = 0.0
    rain_duration_s: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """The parameters as JSON values (inf as the string "inf")."""
        return {k: _jsonable(v) for k, v in asdict(self).items()}


def _draw(rng: np.random.Generator, r: Range | None, how: str) -> float | None:
    """One value of ``r``; a uniform number is drawn whatever ``r`` is, so that every item
    draws the same sequence and adding a range does not move the others."""
    u = float(rng.random())
    if r is None:
        return None
    lo, hi = r
    if lo == hi:
        return lo
    if how == "log":
        return math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
    return lo + u * (hi - lo)


def sample_item(config: DatasetConfig, index: int) -> ItemParams:
    """The parameters of item ``index``, from ``SeedSequence([config.seed, index])`` only.

    Examples
    --------
    >>> cfg = DatasetConfig(out="ds", scene="street", variants=4, seed=3, rain_rate_mm_h="1:50")
    >>> sample_item(cfg, 2) == sample_item(cfg, 2)
    True
    >>> 1.0 <= sample_item(cfg, 2).rain_rate_mm_h <= 50.0
    True
    """
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, integer("index", index, 0, 2**63 - 1)]))
    render_seed = int(rng.integers(0, 2**63 - 1))
    rate = _draw(rng, config.rain_rate_mm_h, "uniform")
    vis = _draw(rng, config.visibility_m, "log")
    exposure = _draw(rng, config.exposure_s, "log")
    f_number = _draw(rng, config.f_number, "log")
    focus = _draw(rng, config.focus_distance_m, "log")
    wind = _draw(rng, config.wind_m_s, "uniform")
    j, jd = config.camera_jitter_m, config.camera_jitter_deg
    dx, dz, dyaw, dpitch = (float(v) for v in rng.uniform(-1.0, 1.0, 4))
    snow = _draw(rng, config.snow_rate_mm_h, "uniform")  # drawn last: the draws before keep their values
    hours = _draw(rng, config.snow_hours, "uniform")
    glass_t = 60.0 * float(rng.random())
    wet_s = _draw(rng, config.rain_duration_s, "uniform")  # drawn last: the draws before keep their values
    assert rate is not None and vis is not None and exposure is not None and wind is not None and snow is not None
    if f_number is not None and focus is None:
        focus = math.inf
    return ItemParams(
        index=index,
        render_seed=render_seed,
        rain_rate_mm_h=rate,
        visibility_m=vis,
        exposure_s=exposure,
        f_number=f_number,
        focus_distance_m=focus,
        wind_m_s=wind,
        camera_dx_m=dx * j,
        camera_dz_m=dz * j,
        camera_dyaw_deg=dyaw * jd,
        camera_dpitch_deg=dpitch * jd / 2.0,
        snow_rate_mm_h=snow,
        snow_hours=hours if hours is not None else 0.0,
        windshield_time_s=glass_t if config.windshield is not None else 0.0,
        rain_duration_s=wet_s if wet_s is not None else 0.0,
    )
