"""The frame renderer: two backends, one result.

``backend="cpu"`` runs the Rust CPU backend (rayon, every pass fused so a pixel is written
once). ``backend="gpu"`` runs the wgpu backend on any Vulkan adapter, Mesa's lavapipe
included. ``backend="auto"`` takes a hardware GPU when there is one and the CPU backend
otherwise: on a software-only machine the CPU backend is much faster than lavapipe.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from skyfall import _core, display, io, sky
from skyfall._validate import choice, flag, in_range, integer, real
from skyfall.camera import Camera
from skyfall.scenes import BoxScene, PhotoScene
from skyfall.weather import Weather

if TYPE_CHECKING:
    from skyfall._core import _Request
    from skyfall.snow import SnowCover

__all__ = ["BACKENDS", "Frame", "Renderer"]

BACKENDS = ("auto", "cpu", "gpu")

_devices: dict[bool, _core.GpuDevice] = {}
_devices_lock = threading.Lock()


def _gpu_device(require_hardware: bool) -> _core.GpuDevice:
    """One device per process and kind, created on first use and shared by every Renderer."""
    with _devices_lock:
        if require_hardware not in _devices:
            if not os.environ.get("XDG_RUNTIME_DIR"):
                # Vulkan loaders warn on stderr without one; a private 0700 folder silences them.
                os.environ["XDG_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="skyfall-xdg-")
            _devices[require_hardware] = _core.GpuDevice(require_hardware=require_hardware)
        return _devices[require_hardware]


def _with_cover(weather: Weather | None, snow_cover: SnowCover | None) -> Weather:
    """The call's weather (clear when None) with a cover given the deprecated way
    (``snow_cover=``) folded in, warning the caller's line (an entry point's own call)."""
    weather = weather if weather is not None else Weather()
    if not isinstance(weather, Weather):
        raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
    if snow_cover is None:
        return weather
    warnings.warn(
        "snow_cover= is deprecated: the cover is part of the weather, Weather(snow_cover=cover) "
        "(or dataclasses.replace(weather, snow_cover=cover))",
        DeprecationWarning,
        stacklevel=3,
    )
    if weather.snow_cover is not None and weather.snow_cover is not snow_cover:
        raise ValueError("snow_cover= and weather.snow_cover are two covers: give one, as Weather(snow_cover=...)")
    return dataclasses.replace(weather, snow_cover=snow_cover)


def _check_apart(scene: BoxScene | PhotoScene, outputs: dict[str, NDArray[Any] | None]) -> None:
    """Refuse output arrays that overlap the scene's photo or depth map, or each other: the
    renderer reads its inputs while it writes (a photo's arrays are the caller's, not copies)."""
    inputs: dict[str, NDArray[Any] | None] = {}
    if isinstance(scene, PhotoScene):
        inputs = {"the scene's image": scene.srgb8 if scene.srgb8 is not None else scene.__dict__.get("image"), "the scene's depth_m": scene.depth_m}
    given = [(name, a) for name, a in outputs.items() if a is not None]
    for i, (name, a) in enumerate(given):
        for other, b in [*inputs.items(), *given[i + 1 :]]:
            if b is not None and np.may_share_memory(a, b):
                raise ValueError(f"{name} overlaps {other}: pass a separate array")


def _check_writable(name: str, a: Any, dtype: type, shape: tuple[int, ...]) -> None:
    """Refuse ``a`` unless Rust can write a frame into it (``dtype``, ``shape``, C-contiguous,
    writable), saying what is wrong with it."""
    want = f"a writable C-contiguous {np.dtype(dtype).name} array of shape {shape}"
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name} must be {want} (numpy), got {type(a).__name__}")
    if a.dtype != dtype:
        problem = f"dtype {a.dtype}"
    elif a.shape != shape:
        problem = f"shape {a.shape}"
    elif not a.flags.c_contiguous:
        problem = "an array that is not C-contiguous"
    elif not a.flags.writeable:
        problem = "a read-only array"
    else:
        return
    raise ValueError(f"{name} must be {want}, got {problem}")


@dataclass
class Frame:
    """A rendered frame.

    Attributes
    ----------
    rgb : ndarray of float32, shape (H, W, 3)
        Linear RGB in units of E/pi (multiply by ``luminance_scale_cd_m2`` for cd/m^2).
    depth_m : ndarray of float32, shape (H, W)
        Depth along the optical axis, m; ``inf`` for sky.
    layers : dict of str to ndarray of float32, shape (H, W)
        Ground-truth layers: the haze pass adds ``transmittance`` (e^(-sigma d)); rain adds
        ``rain_alpha`` (streak coverage 1 - prod(1 - a_i)) and ``rain_depth_m`` (depth of the
        nearest visible streak, inf where none); a snow cover (``Weather(snow_cover=...)``) adds
        ``snow_depth_m`` (the depth of snow on each pixel's surface, 0 where none); clouds
        (``Weather(clouds=...)``) add ``cloud_alpha`` (their coverage 1 - prod(1 - alpha_i)); a
        sky with a sun adds ``sun_transmittance`` on box scenes (the share of the sun's direct
        light reaching each pixel's surface: 0 behind a box, the clouds' Gamma elsewhere, 1 for
        sky): only the layers this frame's passes drew.
        :meth:`layer` gives any layer, with its neutral value where it was not drawn. The
        clean frame is the same render without rain.
    backend : str
        ``"cpu"`` or ``"gpu"``.
    adapter_info : dict or None
        The GPU adapter (name, backend, device_type, driver) for GPU frames.
    luminance_scale_cd_m2 : float
        E/pi of the weather's sky illuminance, cd/m^2.
    stats : dict
        Counters of the passes that ran: ``rain_drops`` (drops generated: the rain region's
        drops, or with billboards the textures' streaks, in the voxels whose streaks can reach
        the view; the others are never generated), ``rain_streaks``
        (streaks drawn), ``rain_culled`` (drops on screen skipped by ``cull_threshold``).

    In Jupyter a frame shows itself: its sRGB image and drawn layers (``_repr_html_``), or the
    image alone as PNG (``_repr_png_``).
    """

    rgb: NDArray[np.float32]
    depth_m: NDArray[np.float32]
    layers: dict[str, NDArray[np.float32]] = field(default_factory=dict)
    backend: str = "cpu"
    adapter_info: dict[str, str] | None = None
    luminance_scale_cd_m2: float = 10000.0 / np.pi
    stats: dict[str, int] = field(default_factory=dict)

    def save(self, path: str | Path, *, exposure: float = 1.0, compression: str | None = None) -> None:
        """Write the frame; the format follows the extension.

        EXR keeps float32 ``R, G, B``, ``depth_m`` and every layer as named channels (read them
        back by name with :func:`skyfall.io.read_channels`; OpenEXR sorts them). 8-bit formats
        (PNG, JPEG) hold ``rgb * exposure`` sRGB-encoded (clipped at 1).

        Parameters
        ----------
        path : str or Path
            The file; ``.exr``, ``.png``, ``.jpg``, ... (what OpenImageIO writes).
        exposure : float
            Scale of the 8-bit formats' linear values before encoding (EXR keeps them as they are).
        compression : str, optional
            EXR only: OpenEXR's compression (``"zip"``, OpenImageIO's default, ``"zips"``,
            ``"piz"``, ``"rle"``, ``"none"``, or a lossy one such as ``"dwaa"``).
        """
        p = Path(path)
        if p.suffix.lower() == ".exr":
            names = ["R", "G", "B", "depth_m", *self.layers]
            stack = np.concatenate([self.rgb, self.depth_m[..., None], *(v[..., None] for v in self.layers.values())], axis=2)
            meta = None if compression is None else {"compression": str(compression)}
            io.write_image(p, stack, channel_names=names, metadata=meta)
        else:
            io.write_image(p, self.rgb * np.float32(real("exposure", exposure)))

    def layer(self, name: str) -> NDArray[np.float32]:
        """One ground-truth layer, whether or not this frame's passes drew it.

        A drawn layer is ``self.layers[name]`` itself. A layer of :data:`skyfall._core.LAYERS`
        that no pass drew (no rain at 0 mm/h, no haze in clear air) comes back as its neutral
        value everywhere, the value the pass would have left (``_core.LAYER_NEUTRAL``, declared
        with the layers in the core: ``rain_alpha`` 0, ``rain_depth_m`` inf, ``transmittance``
        1), as a read-only float32 array of shape (H, W) that costs no memory (one value,
        broadcast).

        Parameters
        ----------
        name : str
            A layer's name, one of ``skyfall._core.LAYERS``.

        Returns
        -------
        ndarray of float32, shape (H, W)

        Raises
        ------
        ValueError
            When ``name`` is not a layer; the message lists the layers.

        Examples
        --------
        >>> from skyfall import Weather, scenes
        >>> frame = Renderer(16, 9, backend="cpu").render(scenes.street(), Weather())
        >>> frame.layers
        {}
        >>> float(frame.layer("rain_alpha").max()), frame.layer("rain_depth_m").shape
        (0.0, (9, 16))
        """
        drawn = self.layers.get(name)
        if drawn is not None:
            return drawn
        if name not in _core.LAYERS:
            raise ValueError(f"name = {name!r} is not a layer: the layers are {', '.join(map(repr, _core.LAYERS))}")
        return np.broadcast_to(np.float32(_core.LAYER_NEUTRAL[name]), self.depth_m.shape)

    def _repr_png_(self) -> bytes | None:
        """The frame as Jupyter shows it: ``io.to_srgb8(self.rgb)`` as PNG bytes
        (:func:`skyfall.display.png_bytes`). None without OpenImageIO (the ``io`` extra): the
        notebook then shows the text repr."""
        try:
            return display.png_bytes(io.to_srgb8(self.rgb))
        except ImportError:
            return None

    def _repr_html_(self) -> str | None:
        """The frame and its drawn layers side by side, small (:func:`skyfall.display.frame_html`);
        None without OpenImageIO, as for :meth:`_repr_png_`."""
        try:
            return display.frame_html(self)
        except ImportError:
            return None


class Renderer:
    """Renders scenes under weather into frames.

    Parameters
    ----------
    width, height : int
        Frame size, px, in [1, 16384].
    backend : {"auto", "cpu", "gpu"}
        See the module docstring. ``"gpu"`` raises :class:`skyfall.GpuUnavailableError` when
        no Vulkan adapter exists, with what to install.

    Attributes
    ----------
    backend : str
        The backend in use, ``"cpu"`` or ``"gpu"``.
    adapter_info : dict or None
        The GPU adapter when ``backend == "gpu"``.

    Examples
    --------
    >>> from skyfall import Weather, scenes
    >>> renderer = Renderer(64, 36, backend="cpu")
    >>> frame = renderer.render(scenes.street(), Weather(rain_rate_mm_h=10.0))
    >>> frame.rgb.shape, frame.depth_m.shape, sorted(frame.layers)
    ((36, 64, 3), (36, 64), ['rain_alpha', 'rain_depth_m', 'transmittance'])
    >>> renderer.render_srgb8(scenes.street(), Weather(rain_rate_mm_h=10.0)).dtype
    dtype('uint8')
    """

    def __init__(self, width: int, height: int, *, backend: str = "auto") -> None:
        self.width = integer("width", width, 1, 16384)
        self.height = integer("height", height, 1, 16384)
        choice("backend", backend, BACKENDS)
        self._device: _core.GpuDevice | None = None
        if backend == "gpu":
            self._device = _gpu_device(require_hardware=False)
        elif backend == "auto":
            try:
                self._device = _gpu_device(require_hardware=True)
            except _core.GpuUnavailableError:
                self._device = None
        self.backend = "gpu" if self._device is not None else "cpu"

    @property
    def adapter_info(self) -> dict[str, str] | None:
        """Name, backend, device type and driver of the GPU adapter, or None on the CPU."""
        if self._device is None:
            return None
        name, backend, device_type, driver = self._device.adapter_info
        return {"name": name, "backend": backend, "device_type": device_type, "driver": driver}

    def render(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        *,
        camera: Camera | None = None,
        time_s: float = 0.0,
        seed: int = 0,
        cull_threshold: float | None = None,
        ambient_spacing_m: float = 1.0,
        ambient_samples: int = sky.MAP_SAMPLES,
        out: Frame | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Frame:
        """Render one frame.

        Parameters
        ----------
        scene : BoxScene or PhotoScene
            What to show. A photo's size must equal the renderer's.
        weather : Weather, optional
            Default: clear (no rain, infinite visibility): the scene unchanged.
        camera : Camera, optional
            Overrides a box scene's camera (photos keep the camera that took them).
        time_s : float
            Time of the frame, s, in [-1e7, 1e7]: drops have fallen v * time_s (wrapping in their 1 m voxels),
            so consecutive times give temporally coherent rain. The haze is static.
        seed : int
            Seed of the rain, in [0, 2^64). Drops are anchored in the world: two cameras or
            two frames with the same seed see the same drops.
        cull_threshold : float, optional
            Skip drops whose received light I_R (relative units; 1.0 is the open sky's) is
            below this, as Yoshida, Dobashi & Yamamoto do for unlit billboards: at dusk with lamps, 1.5 keeps
            only lamp-lit drops. ``frame.stats["rain_culled"]`` counts them. None (default)
            draws every drop.
        ambient_spacing_m : float
            Node spacing of the ambient-light map (:func:`skyfall.sky.ambient_light_map`), m, in
            [0.05, 100]. A box scene's surfaces, every drop's I_R and the haze's airlight read
            the sky light from it; it is built once per scene, sky and spacing and cached.
        ambient_samples : int
            Azimuths per map node, in [4, 65536] (default 64).
        out : Frame, optional
            A previous frame of this size to render into: its arrays are overwritten and come
            back in the new frame (layers this frame does not draw are left out of it; layers
            it draws that ``out`` lacks are new arrays). Fresh arrays cost the kernel's zeroing
            of every page (58 MB per 1080p frame with its layers); reusing them saves that.
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.

        Returns
        -------
        Frame
        """
        weather = _with_cover(weather, snow_cover)
        request = self._request(scene, weather, camera, time_s, seed, cull_threshold, ambient_spacing_m, ambient_samples)
        arrays = self._out_arrays(out) if out is not None else None
        # One core call: the core derives the sky, the haze and its airlight, the rain and its
        # light from the request, and names the layers it drew (skyfall._core.LAYERS).
        rgb, depth, layers, stats = _core.render_frame(request, device=self._device, out=arrays)
        if weather.windshield is not None:
            # The windshield: a full-frame stage after the particles, over either backend's frame.
            from skyfall import windshield as _ws

            glass, drop_layers = _ws.frame_stage(rgb, weather.windshield, request["camera"], time_s=time_s, seed=seed, device=self._device)
            rgb[...] = glass
            layers = {**layers, **drop_layers}
        return Frame(
            rgb=rgb,
            depth_m=depth,
            layers=layers,
            backend=self.backend,
            adapter_info=self.adapter_info,
            luminance_scale_cd_m2=weather.luminance_scale_cd_m2,
            stats=stats,
        )

    def fuses_srgb8(self, scene: BoxScene | PhotoScene, weather: Weather | None = None, snow_cover: SnowCover | None = None) -> bool:
        """Whether :meth:`render_srgb8` of these takes the fused 8-bit path (an 8-bit photo on
        the CPU backend, no windshield, no clouds, no snow cover in the weather: stages that
        path does not draw) rather than rendering the float frame and encoding it.

        Parameters
        ----------
        scene : BoxScene or PhotoScene
            The scene.
        weather : Weather, optional
            The weather (its ``windshield``, ``clouds`` and ``snow_cover``).
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.

        Returns
        -------
        bool
        """
        weather = _with_cover(weather, snow_cover)
        return (
            self._device is None
            and isinstance(scene, PhotoScene)
            and scene.srgb8 is not None
            and weather.windshield is None
            and weather.clouds is None
            and weather.snow_cover is None
        )

    def render_srgb8(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        *,
        camera: Camera | None = None,
        time_s: float = 0.0,
        seed: int = 0,
        cull_threshold: float | None = None,
        ambient_spacing_m: float = 1.0,
        ambient_samples: int = sky.MAP_SAMPLES,
        out: NDArray[np.uint8] | None = None,
        rain_alpha_out: NDArray[np.float32] | None = None,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> NDArray[np.uint8]:
        """Render one frame straight to 8-bit sRGB: the augmentation path.

        The same frame as :meth:`render` followed by :func:`skyfall.io.to_srgb8`, every byte
        within 1 code of it (nearly all equal). For an 8-bit :class:`PhotoScene` on the CPU
        backend the haze and the rain are fused into one pass over bands of rows that decodes,
        hazes, composites and encodes each pixel once, with no frame-sized float buffers: the
        fast way to put rain on a dataset of photos. Other scenes, the GPU backend and weather
        with a windshield render the float frame and encode it.

        Parameters
        ----------
        scene, weather, camera, time_s, seed, cull_threshold, ambient_spacing_m, ambient_samples
            As for :meth:`render`.
        out : ndarray of uint8, shape (H, W, 3), optional
            Where to write the image (C-contiguous); a new array when None. Reusing one
            across frames saves its allocation.
        rain_alpha_out : ndarray of float32, shape (H, W), optional
            Filled with the rain's coverage (``frame.layers["rain_alpha"]``; zeros without
            rain) when given: the ground truth of a deraining dataset.
        snow_alpha_out : ndarray of float32, shape (H, W), optional
            Filled with the snowflakes' coverage (``frame.layers["snow_alpha"]``; zeros
            without snow) when given.
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``
            (a frame with a cover is rendered on the float path and encoded).

        Raises
        ------
        ValueError
            When a photo is not the renderer's size (checked first), when ``out`` or
            ``rain_alpha_out`` has the wrong dtype, shape or layout, or overlaps the scene's
            photo, its depth map or the other output.
        TypeError
            When ``out`` or ``rain_alpha_out`` is not a numpy array.

        Returns
        -------
        ndarray of uint8, shape (H, W, 3)
            The image (``out`` when given).
        """
        weather = _with_cover(weather, snow_cover)
        self._check_srgb8_outputs(scene, out, rain_alpha_out, snow_alpha_out)
        if out is None:
            out = np.empty((self.height, self.width, 3), np.uint8)
        # A windshield or a snow cover is a stage the fused path does not draw: float, then encode.
        if self.fuses_srgb8(scene, weather):
            assert isinstance(scene, PhotoScene) and scene.srgb8 is not None
            request = self._request(scene, weather, camera, time_s, seed, cull_threshold, ambient_spacing_m, ambient_samples)
            _core.render_photo8(
                request, scene.srgb8, io.srgb8_table(), out, rain_alpha_out=rain_alpha_out, snow_alpha_out=snow_alpha_out
            )
            return out
        frame = self.render(
            scene,
            weather,
            camera=camera,
            time_s=time_s,
            seed=seed,
            cull_threshold=cull_threshold,
            ambient_spacing_m=ambient_spacing_m,
            ambient_samples=ambient_samples,
        )
        out[...] = io.to_srgb8(frame.rgb)
        if rain_alpha_out is not None:
            rain_alpha_out[...] = frame.layer("rain_alpha")
        if snow_alpha_out is not None:
            snow_alpha_out[...] = frame.layer("snow_alpha")
        return out

    def _out_arrays(self, out: Frame) -> dict[str, NDArray[np.float32] | None]:
        """``out``'s arrays for ``_core.render_frame``, each checked (None: not in ``out``)."""
        if not isinstance(out, Frame):
            raise TypeError(f"out must be a skyfall.Frame, got {type(out).__name__}")
        shape = (self.height, self.width)
        arrays = {"rgb": out.rgb, "depth_m": out.depth_m, **{k: out.layers.get(k) for k in _core.LAYERS}}
        for name, a in arrays.items():
            if a is not None:
                _check_writable(f"out's {name}", a, np.float32, (*shape, 3) if name == "rgb" else shape)
        return arrays

    def _check_srgb8_outputs(self, scene: Any, out: Any, rain_alpha_out: Any, snow_alpha_out: Any = None) -> None:
        """render_srgb8's outputs, checked after the photo's size (their shapes follow from it)."""
        self._check_photo_size(scene)
        shape = (self.height, self.width)
        if out is not None:
            _check_writable("out", out, np.uint8, (*shape, 3))
        if rain_alpha_out is not None:
            _check_writable("rain_alpha_out", rain_alpha_out, np.float32, shape)
        if snow_alpha_out is not None:
            _check_writable("snow_alpha_out", snow_alpha_out, np.float32, shape)
        _check_apart(scene, {"out": out, "rain_alpha_out": rain_alpha_out, "snow_alpha_out": snow_alpha_out})

    def _check_photo_size(self, scene: Any) -> None:
        """A photo must be the renderer's size (a box scene is rendered at any size)."""
        if isinstance(scene, PhotoScene) and scene.shape != (self.height, self.width):
            h, w = scene.shape
            raise ValueError(
                f"the photo is {w}x{h} px, the renderer {self.width}x{self.height} px: "
                f"render it with a renderer of its size, Renderer({w}, {h})"
            )

    def _request(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather,
        camera: Camera | None,
        time_s: float,
        seed: int,
        cull_threshold: float | None,
        ambient_spacing_m: float,
        ambient_samples: int,
    ) -> _Request:
        """The frame's request for ``_core.render_frame`` and ``_core.render_photo8``: the
        frame's own objects (the core reads them attribute by attribute), with the scene's
        ambient-light map (built once per scene, sky and spacing, and cached)."""
        if not isinstance(weather, Weather):
            raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
        t = in_range("time_s", time_s)
        integer("seed", seed, 0, 2**64 - 1)
        if isinstance(scene, PhotoScene):
            self._check_photo_size(scene)
            cam = scene.camera
        elif isinstance(scene, BoxScene):
            if camera is not None and not isinstance(camera, Camera):
                raise TypeError(f"camera must be a skyfall.Camera, got {type(camera).__name__}")
            cam = (camera if camera is not None else scene.camera).with_resolution(self.width, self.height)
        else:
            raise TypeError(f"scene must be a BoxScene or PhotoScene, got {type(scene).__name__}")
        cull = None if cull_threshold is None else in_range("cull_threshold", cull_threshold)
        request: _Request = {
            "camera": cam,
            "weather": weather,
            "scene": scene,
            "time_s": t,
            "seed": int(seed),
            "cull_threshold": cull,
            "ambient": self._ambient(scene, weather, cam, ambient_spacing_m, ambient_samples),
        }
        if weather.clouds is not None:
            from skyfall import clouds as _clouds

            request["clouds"] = _clouds.frame_field(weather.clouds, weather.sun_direction)
        if weather.snow_cover is not None:
            request["snow_cover"] = weather.snow_cover.core
        return request

    @staticmethod
    def _ambient(
        scene: BoxScene | PhotoScene, weather: Weather, cam: Camera, spacing_m: float, samples: int
    ) -> _core.AmbientLightMap:
        """The frame's ambient-light map (a single node of open sky where nothing hides it), cached."""
        s = in_range("ambient_spacing_m", spacing_m)
        n = integer("ambient_samples", samples, 4, 65_536)
        occluders = np.ascontiguousarray(scene.boxes if isinstance(scene, BoxScene) else scene.occluders, dtype=np.float32)
        if len(occluders) == 0:
            return sky.cached_core_map(occluders, weather, np.zeros(3), np.zeros(3), s, n, "ambient_spacing_m")
        reach = weather.rain_near_m + 1.0 if weather.rain_rate_mm_h > 0 and weather.rain_streaks else 1.0
        lo, hi = sky.default_bounds(scene, s, around_m=cam.position_m, radius_m=reach)
        # The map spans the scene's boxes and the rain region around the camera: say so in the
        # user's terms when that cannot be built (the map's own message names its internals).
        limit = _core.AMBIENT_EXTENT_M
        if not (np.all(np.abs(lo) <= limit) and np.all(np.abs(hi) <= limit)):
            pos = ", ".join(f"{v:g}" for v in cam.position_m)
            raise ValueError(
                f"the camera at position_m = ({pos}) is too far from the scene's boxes: the ambient-light "
                f"map must span both, within [-{limit:g}, {limit:g}] m; put the camera near the boxes "
                "(a box scene's world is the boxes' own; far from the origin, use a PhotoScene)"
            )
        return sky.cached_core_map(occluders, weather, lo, hi, s, n, "ambient_spacing_m")

    def render_sequence(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        *,
        n_frames: int,
        fps: float = 30.0,
        seed: int = 0,
        camera: Camera | None = None,
        start_s: float = 0.0,
        cull_threshold: float | None = None,
        ambient_spacing_m: float = 1.0,
        ambient_samples: int = sky.MAP_SAMPLES,
        out: Frame | None = None,
        progress: bool = False,
        snow_cover: SnowCover | None = None,
    ) -> Iterator[Frame]:
        """Render ``n_frames`` consecutive frames at ``fps``, one at a time: temporally
        coherent rain.

        Frame k is :meth:`render` at ``time_s = start_s + k / fps`` with the same seed, bit
        for bit. Frames are rendered as the iterator is advanced and none is kept, so a clip
        takes one frame's memory however long it is (``list(...)`` keeps them all). Streak
        length follows the camera's ``exposure_s`` (v * T), which should not exceed 1/fps.

        Parameters
        ----------
        scene, weather, camera, seed, cull_threshold, ambient_spacing_m, ambient_samples
            As for :meth:`render`.
        n_frames : int
            Number of frames, in [1, 1e6].
        fps : float
            Frames per second, in (0, 10000].
        start_s : float
            Time of the first frame, s; every frame's time must lie in [-1e7, 1e7] s.
        out : Frame, optional
            A frame of this size to render every frame into (see :meth:`render`): each
            frame yielded then holds ``out``'s arrays, so it is overwritten by the next one;
            copy what you keep (``frame.rgb.copy()``). None: fresh arrays for every frame.
        progress : bool
            Show a tqdm progress bar while the frames are rendered.
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.

        Returns
        -------
        iterator of Frame

        Raises
        ------
        ValueError, TypeError
            Every argument is checked when this is called, before the first frame.
        """
        weather = _with_cover(weather, snow_cover)
        if out is not None:
            self._out_arrays(out)
        times, options = self._sequence_args(
            scene, weather, camera, n_frames, fps, start_s, seed, cull_threshold, ambient_spacing_m, ambient_samples, progress
        )

        def frames() -> Iterator[Frame]:
            into = out
            for t in times:
                frame = self.render(scene, weather, time_s=t, out=into, **options)
                if out is not None:
                    into = frame  # out's arrays, and any layer the first frame added to them
                yield frame

        return frames()

    def render_sequence_srgb8(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        *,
        n_frames: int,
        fps: float = 30.0,
        seed: int = 0,
        camera: Camera | None = None,
        start_s: float = 0.0,
        cull_threshold: float | None = None,
        ambient_spacing_m: float = 1.0,
        ambient_samples: int = sky.MAP_SAMPLES,
        out: NDArray[np.uint8] | None = None,
        rain_alpha_out: NDArray[np.float32] | None = None,
        progress: bool = False,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Iterator[NDArray[np.uint8]]:
        """:meth:`render_sequence` in 8-bit sRGB: each frame is :meth:`render_srgb8` at
        ``time_s = start_s + k / fps``, byte for byte.

        Parameters
        ----------
        scene, weather, n_frames, fps, seed, camera, start_s, cull_threshold, ambient_spacing_m, ambient_samples, progress, snow_cover
            As for :meth:`render_sequence` (``snow_cover`` deprecated).
        out : ndarray of uint8, shape (H, W, 3), optional
            Where to write every frame: each array yielded is then ``out``, overwritten by
            the next frame. None: a new array per frame.
        rain_alpha_out : ndarray of float32, shape (H, W), optional
            Filled with each frame's rain coverage as its image is yielded (overwritten by
            the next frame).
        snow_alpha_out : ndarray of float32, shape (H, W), optional
            The same for the snowflakes' coverage.

        Returns
        -------
        iterator of ndarray of uint8, shape (H, W, 3)

        Raises
        ------
        ValueError, TypeError
            Every argument is checked when this is called, before the first frame (see
            :meth:`render_srgb8`).
        """
        weather = _with_cover(weather, snow_cover)
        self._check_srgb8_outputs(scene, out, rain_alpha_out, snow_alpha_out)
        times, options = self._sequence_args(
            scene, weather, camera, n_frames, fps, start_s, seed, cull_threshold, ambient_spacing_m, ambient_samples, progress
        )

        def frames() -> Iterator[NDArray[np.uint8]]:
            for t in times:
                yield self.render_srgb8(
                    scene, weather, time_s=t, out=out, rain_alpha_out=rain_alpha_out, snow_alpha_out=snow_alpha_out, **options
                )

        return frames()

    def _sequence_args(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather,
        camera: Camera | None,
        n_frames: int,
        fps: float,
        start_s: float,
        seed: int,
        cull_threshold: float | None,
        ambient_spacing_m: float,
        ambient_samples: int,
        progress: bool,
    ) -> tuple[Iterator[float], dict[str, Any]]:
        """A sequence's arguments, all checked now (as :meth:`render` checks them): its frame
        times (behind a progress bar, started at the first frame) and the keyword arguments
        every frame is rendered with."""
        times = _frame_times(n_frames, fps, start_s)
        show = flag("progress", progress)
        self._request(scene, weather, camera, times(0), seed, cull_threshold, ambient_spacing_m, ambient_samples)
        options: dict[str, Any] = dict(
            camera=camera, seed=seed, cull_threshold=cull_threshold, ambient_spacing_m=ambient_spacing_m, ambient_samples=ambient_samples
        )
        return _progress(times, show), options


class _FrameTimes:
    """Frame k's time, ``start_s + k / fps``, for k < n (checked once, computed as needed)."""

    def __init__(self, start: float, rate: float, n: int) -> None:
        self.start, self.rate, self.n = start, rate, n

    def __call__(self, k: int) -> float:
        return self.start + k / self.rate

    def __len__(self) -> int:
        return self.n

    def __iter__(self) -> Iterator[float]:
        return (self(k) for k in range(self.n))


def _frame_times(n_frames: int, fps: float, start_s: float) -> _FrameTimes:
    n = integer("n_frames", n_frames, 1, 1_000_000)
    rate = real("fps", fps)
    if not 0.0 < rate <= 10000.0:
        raise ValueError(f"fps = {rate} is outside the valid range (0, 10000]")
    times = _FrameTimes(real("start_s", start_s), rate, n)
    start, end = times(0), times(n - 1)
    if not (abs(start) <= 1e7 and abs(end) <= 1e7):
        raise ValueError(f"start_s = {start_s} and fps = {fps} put frame times at [{start}, {end}] s, outside the valid range [-1e7, 1e7] s")
    return times


def _progress(times: _FrameTimes, show: bool) -> Iterator[float]:
    """The frame times, behind a tqdm bar when ``show`` (closed when the frames stop)."""
    if not show:
        yield from times
        return
    from tqdm import tqdm  # type: ignore[import-untyped]

    with tqdm(times, total=len(times), unit="frame") as bar:
        yield from bar
