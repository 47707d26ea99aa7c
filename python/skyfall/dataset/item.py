"""One dataset item: its scene, its weather, its frame and its files.

An item is a function of the run's options and its index alone (:func:`render_item`), so a
worker process, the main process or a later resumed run all write the same bytes for it.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import skyfall
from skyfall import io, scenes, sky
from skyfall.camera import Camera
from skyfall.dataset.io import DEPTH_EXTENSIONS, NpyStack, atomic_write, read_depth, read_photo, sha256_file, write_json, write_npy, write_png
from skyfall.dataset.sample import DatasetConfig, ItemParams, sample_item
from skyfall.io import encode_srgb
from skyfall.photo import assumed_depth, estimate_sky_mask, exif_vertical_fov_deg, level_camera, sky_level_camera
from skyfall.photo_scene import DEFAULT_DISTANCE_M
from skyfall.render import Frame, Renderer
from skyfall.depth_io import format_for
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.snow import SnowCover
from skyfall.weather import Weather

__all__ = ["COSTS", "ItemSource", "Staged", "Worker", "item_files", "prepare", "render_item", "render_items", "render_stage", "verify_item", "write_stage"]

COSTS = ("read", "render", "encode", "write")
"""The parts of an item's cost, s: ``read`` (input files, the scene and its airlight),
``render`` (the weather frame and the clean one), ``encode`` (sRGB encoding and OpenImageIO's
PNG/EXR writing, its zlib compression, into the page cache) and ``write`` (the layers' .npy
files, the checksums, the renames and the item's manifest row)."""

@dataclass(frozen=True)
class ItemSource:
    """Where item ``index`` comes from: a photo (and its depth map) or the bundled scene.

    Attributes
    ----------
    index : int
        The item's index in the run (photo k's variant v is k * variants + v).
    image, depth : Path or None
        The photo and its depth map (None: a scene item, or no depth folder).
    depth_missing : bool
        A depth folder was given and holds no map for this photo: an error for the item.
    """

    index: int
    image: Path | None = None
    depth: Path | None = None
    depth_missing: bool = False


def item_name(index: int) -> str:
    """The file stem of item ``index``: its index, zero-padded to 6 digits."""
    return f"{index:06d}"


def item_files(config: DatasetConfig, index: int) -> list[str]:
    """The names of item ``index``'s image files in ``out/items`` (its row ``NNNNNN.json`` aside):
    the clips (``.rain.mp4``, ``.clean.mp4``) instead of the PNGs with ``config.sequence``."""
    stem = item_name(index)
    if config.sequence is not None:
        return [f"{stem}.rain.mp4", f"{stem}.clean.mp4", *(f"{stem}.{layer}.npy" for layer in config.layers)]
    names = [f"{stem}.rain.png", f"{stem}.clean.png", *(f"{stem}.{layer}.npy" for layer in config.layers)]
    if config.exr:
        names.append(f"{stem}.rain.exr")
    return names


class Worker:
    """What one worker keeps between items: its renderers (one per frame size, made once),
    the last photo it read and the bundled scene."""

    def __init__(self, config: DatasetConfig) -> None:
        self.config = config
        self._renderers: dict[tuple[int, int], Renderer] = {}
        self._photo: tuple[Path, NDArray[Any], str | None, dict[str, Any]] | None = None
        self._photo_scene: dict[str, Any] = {}  # the last photo's sky mask and estimated depth
        self._street: BoxScene | None = None
        self._clean: tuple[Path, bytes] | None = None  # a photo's clean PNG, the same for each variant

    def renderer(self, width: int, height: int) -> Renderer:
        """This worker's renderer of the size (the last four sizes are kept)."""
        key = (width, height)
        if key not in self._renderers:
            if len(self._renderers) >= 4:
                self._renderers.pop(next(iter(self._renderers)))
            self._renderers[key] = Renderer(width, height, backend=self.config.backend)
        return self._renderers[key]

    def photo(self, path: Path) -> tuple[NDArray[Any], str | None, dict[str, Any]]:
        """The photo at ``path`` with its encoding and header (kept while the next items are
        its variants)."""
        if self._photo is None or self._photo[0] != path:
            image, encoding, meta = read_photo(path, with_metadata=True)
            self._photo = (path, image, encoding, meta)
            self._photo_scene = {}
        return self._photo[1], self._photo[2], self._photo[3]

    def photo_value(self, key: str, make: Any) -> Any:
        """A value derived from the current photo alone (its sky mask, its estimated depth),
        made once for all its variants."""
        if key not in self._photo_scene:
            self._photo_scene[key] = make()
        return self._photo_scene[key]

    def clean_png(self, final: Path, photo: Path, image: NDArray[Any]) -> str:
        """Write ``image`` (the photo ``photo`` itself) as ``final``; a photo's variants reuse
        the bytes encoded for the first (OpenImageIO's PNG bytes are a function of the pixels)."""
        if self._clean is not None and self._clean[0] == photo:
            data = self._clean[1]

            def copy(p: Path) -> None:
                p.write_bytes(data)

            return atomic_write(final, copy)
        digest = write_png(final, image, self.config.png_compression)
        self._clean = (photo, final.read_bytes())
        return digest

    def street(self) -> BoxScene:
        """The bundled street, made once."""
        if self._street is None:
            self._street = scenes.street()
            # A worker renders the street under many weathers: its first sky is lit from the
            # street's horizon, which every later one reuses (the same bits, one direct build
            # fewer per worker).
            sky.expect_sweeps()
        return self._street


def _weather(config: DatasetConfig, p: ItemParams) -> Weather:
    glass = None
    if config.windshield is not None:
        from skyfall.windshield import warm

        glass = warm(config.windshield, p.windshield_time_s, seed=config.seed)
    return Weather(
        rain_rate_mm_h=p.rain_rate_mm_h,
        snow_rate_mm_h=p.snow_rate_mm_h,
        visibility_m=p.visibility_m,
        wind_m_s=(p.wind_m_s, 0.0, 0.0),
        rain_near_m=config.rain_near_m,
        rain_far_m=config.rain_far_m,
        windshield=glass,
        clouds=config.clouds,
        rain_duration_s=p.rain_duration_s,
    )


COVER_DT_S = 300.0
"""The time step of an item's snow cover, s (one step when the cover is shorter)."""


def _cover(config: DatasetConfig, scene: BoxScene | PhotoScene, weather: Weather, p: ItemParams) -> SnowCover | None:
    """The item's snow cover: its snow rate and wind over ``p.snow_hours`` (None: no cover)."""
    if p.snow_hours <= 0.0 or p.snow_rate_mm_h <= 0.0:
        return None
    from skyfall import snow

    return snow.accumulate(scene, weather, duration_s=p.snow_hours * 3600.0, dt_s=COVER_DT_S, resolution_m=config.snow_resolution_m, seed=p.render_seed)


def _item_path(config: DatasetConfig, scene: BoxScene | PhotoScene, weather: Weather, renderer: Renderer) -> str:
    """Which path makes a still or a clip's frames (the row's ``path``): ``"float"`` when the
    EXR is asked for (it needs the float frame: rendered, then encoded), else
    :meth:`Renderer.render_srgb8`'s own (:meth:`Renderer.srgb8_path`): ``"srgb8"`` for its
    fused path, ``"banded"`` for its stages band by band (or ``"float"`` on the GPU backend).
    The bytes are the float frame's either way (the fused path's
    within 1 code)."""
    if config.exr:
        return "float"
    path = renderer.srgb8_path(scene, weather, layers=config.layers)
    return "srgb8" if path == "fused" else path


def _lens(p: ItemParams) -> dict[str, Any]:
    return {"exposure_s": p.exposure_s, "f_number": p.f_number, "focus_distance_m": p.focus_distance_m}


def _street_camera(base: Camera, p: ItemParams) -> Camera:
    x, y, z = (float(v) for v in base.position_m)
    return Camera(
        (x + p.camera_dx_m, y, z + p.camera_dz_m),
        yaw_deg=base.yaw_deg + p.camera_dyaw_deg,
        pitch_deg=base.pitch_deg + p.camera_dpitch_deg,
        vertical_fov_deg=base.vertical_fov_deg,
        **_lens(p),
    )


def _photo_scene(worker: Worker, src: ItemSource, p: ItemParams, row: dict[str, Any]) -> PhotoScene:
    """The item's photo scene: its depth from a file, estimated, or assumed (the photo scene
    model: everything not sky at ``distance_m``, the ground plane only when asked for)."""
    cfg = worker.config
    assert src.image is not None
    if src.depth_missing:
        raise FileNotFoundError(f"no depth map for {src.image.name} in depth = {str(cfg.depth)!r} (looked for {src.image.stem}{'/'.join(DEPTH_EXTENSIONS)})")
    image, encoding, meta = worker.photo(src.image)
    h, w = image.shape[:2]
    if meta.get("alpha_dropped"):
        row["alpha_dropped"] = True
    fov, fov_source = cfg.vertical_fov_deg, "option"
    if fov is None:
        exif = exif_vertical_fov_deg(meta, w, h)
        fov, fov_source = (exif, "exif") if exif is not None else (60.0, "default")
    row["vertical_fov_deg"], row["fov_source"] = fov, fov_source
    ground = cfg.camera_height_m is not None or cfg.horizon_row is not None
    sky = None if src.depth is not None else worker.photo_value("sky_mask", lambda: estimate_sky_mask(image, encoding=encoding))
    if ground:
        height_m = 1.6 if cfg.camera_height_m is None else cfg.camera_height_m
        level = level_camera(w, h, camera_height_m=height_m, horizon_row=cfg.horizon_row, vertical_fov_deg=fov)
        cam = Camera(tuple(level.position_m), pitch_deg=level.pitch_deg, vertical_fov_deg=fov, width=w, height=h, **_lens(p))
        row["camera_height_m"] = height_m
        row["horizon_row"] = cfg.horizon_row if cfg.horizon_row is not None else h / 2.0
    elif src.depth is None and cfg.depth != "estimate":
        level = sky_level_camera(w, h, sky, vertical_fov_deg=fov)
        cam = Camera((0.0, 0.0, 0.0), pitch_deg=level.pitch_deg, vertical_fov_deg=fov, width=w, height=h, **_lens(p))
    else:
        cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=fov, width=w, height=h, **_lens(p))
    if src.depth is not None:
        depth = read_depth(src.depth, cfg.depth_scale_m, cfg.depth_format)
        row["depth_source"] = "file"
        row["depth_format"] = cfg.depth_format if cfg.depth_format is not None else format_for(src.depth)
        row["depth_scale_m"] = cfg.depth_scale_m  # the scale the integer map was read with (None: float metres)
        return PhotoScene(image, depth, camera=cam, encoding=encoding)
    assert sky is not None
    row["sky_share"] = float(np.count_nonzero(sky)) / sky.size
    if cfg.depth == "estimate":
        from skyfall import depth as depth_net

        def estimated() -> NDArray[np.float32]:
            coded = image if encoding in (None, "srgb") else encode_srgb(np.clip(image / max(float(np.quantile(image, 0.999)), 1e-12), 0.0, 1.0))
            return depth_net.estimate(
                coded,
                model=cfg.depth_model if cfg.depth_model is not None else "depth-anything-v2-small",
                camera_height_m=cfg.camera_height_m,
                horizon_row=cfg.horizon_row,
                vertical_fov_deg=fov,
                distance_m=cfg.distance_m,
                sky_mask=sky,
            )

        row["depth_source"] = "estimate"
        row["depth_model"] = cfg.depth_model if cfg.depth_model is not None else "depth-anything-v2-small"
        return PhotoScene(image, worker.photo_value("estimated_depth", estimated), camera=cam, encoding=encoding)
    row["distance_m"] = cfg.distance_m if cfg.distance_m is not None else DEFAULT_DISTANCE_M
    row["depth_source"] = "ground_plane" if ground else "distance"
    depth = assumed_depth(cam, sky_mask=sky, distance_m=row["distance_m"], ground_plane=ground)
    return PhotoScene(image, depth, camera=cam, encoding=encoding)


def prepare(
    worker: Worker, src: ItemSource, p: ItemParams, row: dict[str, Any]
) -> tuple[BoxScene | PhotoScene, Camera | None, Weather]:
    """An item's scene, camera (None: the photo's own) and weather; ``row`` gets the depth
    source, the camera and the frame size.

    Raises
    ------
    FileNotFoundError, OSError, ValueError, TypeError
        For a missing, unreadable or mismatched input, or parameters the renderer refuses.
    """
    cfg = worker.config
    weather = _weather(cfg, p)
    if src.image is None:
        street = worker.street()
        assert street.camera is not None
        camera = _street_camera(street.camera, p)
        row["depth_source"] = "scene"
        row["camera_position_m"] = [float(v) for v in camera.position_m]
        row["camera_yaw_deg"], row["camera_pitch_deg"] = camera.yaw_deg, camera.pitch_deg
        row["width"], row["height"] = cfg.width, cfg.height
        return street, camera, weather
    scene = _photo_scene(worker, src, p, row)
    row["height"], row["width"] = scene.shape
    _ = scene.airlight_linear  # estimated here, counted as reading
    return scene, None, weather


@dataclass
class Staged:
    """An item rendered and not yet written: what :func:`write_stage` encodes and writes.

    Attributes
    ----------
    src : ItemSource
        The item.
    row : dict
        Its manifest row so far (``status`` "error" and ``error`` when rendering failed: then
        nothing is left to write but the row).
    times : dict of str to float
        Its cost so far, s, under :data:`COSTS`.
    rainy, clean : ndarray or None
        The weather and clean images, uint8 (H, W, 3) (None for a clip, written already).
    layers : dict of str to ndarray
        The ground-truth layers asked for, float32 (H, W).
    frame : Frame or None
        The float frame, for its EXR.
    """

    src: ItemSource
    row: dict[str, Any]
    times: dict[str, float]
    rainy: NDArray[np.uint8] | None = None
    clean: NDArray[np.uint8] | None = None
    layers: dict[str, NDArray[np.float32]] = field(default_factory=dict)
    frame: Frame | None = None


def render_item(worker: Worker, src: ItemSource, times: dict[str, float] | None = None) -> dict[str, Any]:
    """Render item ``src.index`` and write its files into ``config.out / "items"``:
    :func:`render_stage`, then :func:`write_stage` (:func:`render_items` overlaps the two
    across items).

    Parameters
    ----------
    worker : Worker
        The process's renderers and caches.
    src : ItemSource
        The item's input.
    times : dict, optional
        Accumulates the item's cost in s under :data:`COSTS`.

    Returns
    -------
    dict
        The item's manifest row (also written as ``items/NNNNNN.json``, last, once its files
        are in place): ``status`` "ok" with ``files`` (name: sha256), or "error" with ``error``
        (the exception's type and message; the run goes on).
    """
    return write_stage(worker, render_stage(worker, src, times))


def render_items(worker: Worker, srcs: Iterable[ItemSource]) -> Iterator[tuple[dict[str, Any], dict[str, float]]]:
    """The items' (row, cost) in order, each item's encoding and writing (one thread) running
    while the next one renders: OpenImageIO's zlib and the renderer both release the GIL, so
    the two share the cores, and with one worker its items/s is set by the larger of the two
    stages instead of their sum. At most one item waits to be written.

    On an exception (Ctrl-C in the rendering thread) the item being written is finished before
    it propagates, so every item whose row exists is complete."""
    with ThreadPoolExecutor(1, thread_name_prefix="skyfall-write") as writer:
        waiting: Future[dict[str, Any]] | None = None
        waiting_times: dict[str, float] = {}
        try:
            for src in srcs:
                staged = render_stage(worker, src)
                if waiting is not None:
                    yield waiting.result(), waiting_times
                waiting, waiting_times = writer.submit(write_stage, worker, staged), staged.times
            if waiting is not None:
                row, waiting = waiting.result(), None
                yield row, waiting_times
        finally:
            if waiting is not None:
                waiting.result()


def _error_row(cfg: DatasetConfig, src: ItemSource, row: dict[str, Any], e: BaseException) -> dict[str, Any]:
    """Record ``e`` as the item's error: its files removed, its row written."""
    folder = cfg.out / "items"
    left = []
    for name in item_files(cfg, src.index):
        try:
            (folder / name).unlink(missing_ok=True)
        except OSError:  # not a file we can remove (a folder in its place): say so in the row
            left.append(name)
    row.pop("files", None)
    row["status"] = "error"
    row["error"] = f"{type(e).__name__}: {e}" + (f" (could not remove {', '.join(left)})" if left else "")
    write_json(folder / f"{item_name(src.index)}.json", row)
    return row


def render_stage(worker: Worker, src: ItemSource, times: dict[str, float] | None = None) -> Staged:
    """Read, sample and render item ``src.index`` (a clip is rendered and written here, its
    frames streamed to the encoder). An error is recorded in the returned row."""
    cfg = worker.config
    t = times if times is not None else {}
    for k in COSTS:
        t.setdefault(k, 0.0)
    p = sample_item(cfg, src.index)
    row: dict[str, Any] = {
        "index": src.index,
        "seed": cfg.seed,
        "skyfall_version": skyfall.__version__,
        "config_sha256": cfg.sha256(),
        "params": p.to_json(),
        "rain_near_m": cfg.rain_near_m,
    }
    if src.image is not None:
        row["image"] = src.image.name
        row["depth"] = None if src.depth is None else src.depth.name
    else:
        row["scene"] = cfg.scene
    staged = Staged(src, row, t)
    try:
        t0 = time.perf_counter()
        scene, camera, weather = prepare(worker, src, p, row)
        h, w = int(row["height"]), int(row["width"])
        renderer = worker.renderer(w, h)
        t1 = time.perf_counter()
        t["read"] += t1 - t0
        cover = _cover(cfg, scene, weather, p)
        if cover is not None:
            weather = dataclasses.replace(weather, snow_cover=cover)
        if cfg.sequence is not None:
            _render_clip(worker, renderer, scene, camera, weather, p, row, t)
            return staged
        path = _item_path(cfg, scene, weather, renderer)
        row["path"] = path
        kw: dict[str, Any] = {"seed": p.render_seed, "ambient_spacing_m": cfg.ambient_spacing_m}
        if cover is not None:
            row["snow_cover"] = {"mean_depth_m": float(np.mean(cover.depth_m)), "spacing_m": float(cover.spacing_m)}
        if path != "float":
            staged.rainy, drawn = renderer.render_srgb8(scene, weather, camera=camera, layers=cfg.layers, **kw)
            staged.layers.update(drawn)
        else:
            frame = renderer.render(scene, weather, camera=camera, **kw)
            staged.layers = {name: frame.layer(name) for name in cfg.layers}
            staged.frame = frame
        if isinstance(scene, PhotoScene):
            staged.clean = scene.srgb8 if scene.srgb8 is not None else io.to_srgb8(scene.image)
        else:
            # no weather, no cover: the 8-bit output's bytes are the float frame's, encoded
            staged.clean = renderer.render_srgb8(scene, Weather(), camera=camera, ambient_spacing_m=cfg.ambient_spacing_m)
        if staged.frame is not None:
            staged.rainy = io.to_srgb8(staged.frame.rgb)
        t["render"] += time.perf_counter() - t1
    except Exception as e:  # an error of this item: recorded, the run goes on
        staged.row = _error_row(cfg, src, row, e)
    return staged


def write_stage(worker: Worker, staged: Staged) -> dict[str, Any]:
    """Encode and write a :func:`render_stage` item's files, then its row (last); its row."""
    cfg = worker.config
    src, row, t = staged.src, staged.row, staged.times
    folder = cfg.out / "items"
    stem = item_name(src.index)
    if row.get("status") == "error":
        return row
    if staged.rainy is None:  # a clip: its files are written
        write_json(folder / f"{stem}.json", row)
        return row
    try:
        files: dict[str, str] = {}
        names = item_files(cfg, src.index)
        files[names[0]] = _timed_png(folder / names[0], staged.rainy, cfg.png_compression, t, cfg.png_strategy)
        assert staged.clean is not None
        if src.image is not None:
            t5 = time.perf_counter()
            files[names[1]] = worker.clean_png(folder / names[1], src.image, staged.clean)
            t["encode"] += time.perf_counter() - t5
        else:
            files[names[1]] = _timed_png(folder / names[1], staged.clean, cfg.png_compression, t)
        if cfg.exr:
            frame = staged.frame
            assert frame is not None
            exr = folder / f"{stem}.rain.exr"
            t3 = time.perf_counter()
            files[exr.name] = atomic_write(exr, lambda path: frame.save(path, compression=cfg.exr_compression))
            t["encode"] += time.perf_counter() - t3
        t4 = time.perf_counter()
        for name in cfg.layers:
            files[f"{stem}.{name}.npy"] = write_npy(folder / f"{stem}.{name}.npy", staged.layers[name])
        row["files"] = dict(sorted(files.items()))
        row["status"] = "ok"
        row["mean_rain_alpha"] = float(np.mean(staged.layers["rain_alpha"], dtype=np.float64)) if "rain_alpha" in staged.layers else None
        write_json(folder / f"{stem}.json", row)
        t["write"] += time.perf_counter() - t4
    except Exception as e:  # an error of this item: recorded, the run goes on
        row = _error_row(cfg, src, row, e)
    return row


def _render_clip(
    worker: Worker,
    renderer: Renderer,
    scene: BoxScene | PhotoScene,
    camera: Camera | None,
    weather: Weather,
    p: ItemParams,
    row: dict[str, Any],
    t: dict[str, float],
) -> None:
    """Write an item's clip: frame k at ``time_s = k / fps`` streamed to the encoder as it is
    rendered (one frame in memory, never N), the clean clip (the photo, or the street rendered
    once without weather, repeated) and each layer as one preallocated (N, H, W) float32 stack,
    a memory map of its temporary ``.npy`` file (:class:`~skyfall.dataset.io.NpyStack`), so an
    item's memory is one frame's however long the clip. ``row`` gets the files' sha256, the
    clip's frames and fps; ``t`` the cost (``render``: the frames, ``encode``: the video encoder,
    ``write``: the stacks' checksums and renames)."""
    cfg = worker.config
    assert cfg.sequence is not None
    h, w = int(row["height"]), int(row["width"])
    folder = cfg.out / "items"
    stem = item_name(p.index)
    row["sequence"], row["fps"], row["video_lossless"] = cfg.sequence, cfg.fps, cfg.video_lossless
    # each layer's (N, H, W) stack mapped from its temporary file, filled frame by frame
    files_out = {name: NpyStack(folder / f"{stem}.{name}.npy", (cfg.sequence, h, w)) for name in cfg.layers}
    try:
        _write_clip(worker, renderer, scene, camera, weather, p, row, t, files_out)
    except BaseException:
        for f in files_out.values():
            f.discard()
        raise


def _write_clip(
    worker: Worker,
    renderer: Renderer,
    scene: BoxScene | PhotoScene,
    camera: Camera | None,
    weather: Weather,
    p: ItemParams,
    row: dict[str, Any],
    t: dict[str, float],
    files_out: dict[str, NpyStack],
) -> None:
    """:func:`_render_clip`'s work, the layer stacks given."""
    from skyfall import video

    cfg = worker.config
    assert cfg.sequence is not None
    n, fps = cfg.sequence, cfg.fps
    h, w = int(row["height"]), int(row["width"])
    folder = cfg.out / "items"
    stacks = {name: f.array for name, f in files_out.items()}
    path = _item_path(cfg, scene, weather, renderer)  # a clip has no EXR: render_srgb8's path
    row["path"] = path
    kw: dict[str, Any] = {"n_frames": n, "fps": fps, "seed": p.render_seed, "ambient_spacing_m": cfg.ambient_spacing_m}
    render_s = [0.0]

    def rainy() -> Iterator[NDArray[np.uint8]]:
        """The rainy frames in order, each filling its slice of the layer stacks."""
        t0 = time.perf_counter()
        if path != "float":
            bufs = {name: np.empty((h, w), np.float32) for name in stacks}
            images = renderer.render_sequence_srgb8(scene, weather, camera=camera, out=np.empty((h, w, 3), np.uint8), layers=bufs, **kw)
            for k, (image, _) in enumerate(images):
                for name, buf in bufs.items():
                    stacks[name][k] = buf
                render_s[0] += time.perf_counter() - t0
                yield image
                t0 = time.perf_counter()
            return
        for k, frame in enumerate(renderer.render_sequence(scene, weather, camera=camera, **kw)):
            for name, stack in stacks.items():
                stack[k] = frame.layer(name)
            image = io.to_srgb8(frame.rgb)
            del frame  # the float frame goes before the next is rendered
            render_s[0] += time.perf_counter() - t0
            yield image
            t0 = time.perf_counter()

    files: dict[str, str] = {}
    names = item_files(cfg, p.index)
    t0 = time.perf_counter()
    files[names[0]] = atomic_write(folder / names[0], lambda tmp: _clip(video, tmp, rainy(), fps, cfg.video_lossless, n))
    t1 = time.perf_counter()
    t["render"] += render_s[0]
    t["encode"] += t1 - t0 - render_s[0]
    if isinstance(scene, PhotoScene) and scene.srgb8 is not None:
        clean: NDArray[np.uint8] = scene.srgb8
    elif isinstance(scene, PhotoScene):
        clean = io.to_srgb8(scene.image)
    else:
        clean = io.to_srgb8(renderer.render(scene, Weather(), camera=camera, ambient_spacing_m=cfg.ambient_spacing_m).rgb)
    t2 = time.perf_counter()
    t["render"] += t2 - t1
    files[names[1]] = atomic_write(folder / names[1], lambda tmp: _clip(video, tmp, (clean for _ in range(n)), fps, cfg.video_lossless, n))
    t3 = time.perf_counter()
    t["encode"] += t3 - t2
    row["mean_rain_alpha"] = float(np.mean(stacks["rain_alpha"], dtype=np.float64)) if "rain_alpha" in stacks else None
    del stacks
    for name, f in files_out.items():
        files[f.final.name] = f.commit()
    row["files"] = dict(sorted(files.items()))
    row["status"] = "ok"
    t["write"] += time.perf_counter() - t3


def _clip(video: Any, path: Path, frames: Iterator[NDArray[np.uint8]], fps: float, lossless: bool, n: int) -> None:
    """``frames`` encoded into ``path`` (an ``.mp4`` name) by :func:`skyfall.video.write_video`."""
    written = video.write_video(path, frames, fps=fps, lossless=lossless)
    if written != n:  # pragma: no cover - the renderer yields n frames
        raise RuntimeError(f"{path.name}: {written} frames written, {n} expected")


def _timed_png(path: Path, image: NDArray[Any], level: int, t: dict[str, float], strategy: str = "default") -> str:
    t0 = time.perf_counter()
    digest = write_png(path, image, level, strategy)
    t["encode"] += time.perf_counter() - t0
    return digest


def verify_item(config: DatasetConfig, index: int) -> bool:
    """Whether item ``index`` is complete: its row says "ok" for these options and every file
    it lists is there with its checksum (what ``resume`` keeps)."""
    import json

    folder = config.out / "items"
    path = folder / f"{item_name(index)}.json"
    try:
        row = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    if not isinstance(row, dict) or row.get("status") != "ok" or row.get("config_sha256") != config.sha256():
        return False
    files = row.get("files", {})
    if set(files) != set(item_files(config, index)):
        return False
    for name, digest in files.items():
        try:
            if sha256_file(folder / name) != digest:
                return False
        except OSError:
            return False
    return True
