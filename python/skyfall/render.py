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
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, NamedTuple, overload

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

__all__ = ["BACKENDS", "FUSED_LAYERS", "Frame", "Renderer", "Srgb8Frame"]

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


FUSED_LAYERS = ("rain_alpha", "snow_alpha")
"""The layers the fused 8-bit path fills (:meth:`Renderer.fuses_srgb8`); asking
:meth:`Renderer.render_srgb8` for any other takes the float path."""


class Srgb8Frame(NamedTuple):
    """:meth:`Renderer.render_srgb8` with ``layers``: the image and the layers asked for
    (unpack it as ``image, layers = ...``).

    Attributes
    ----------
    image : ndarray of uint8, shape (H, W, 3)
        The 8-bit sRGB image (the call's ``out`` when given).
    layers : dict of str to ndarray of float32, shape (H, W)
        Each asked layer, in the order asked, with its neutral value where no pass drew it
        (the call's own arrays when ``layers`` was a dict of them).
    """

    image: NDArray[np.uint8]
    layers: dict[str, NDArray[np.float32]]


@dataclass(frozen=True)
class _Options:
    """A render call's options that hold for every frame of it, checked once
    (:meth:`checked`): what the four entry points share (a sequence checks them before its
    first frame). The defaults are the entry points'."""

    camera: Camera | None = None
    seed: int = 0
    cull_threshold: float | None = None
    ambient_spacing_m: float = 1.0
    ambient_samples: int = sky.MAP_SAMPLES
    layers: tuple[str, ...] | None = None

    @classmethod
    def checked(
        cls,
        camera: Any,
        seed: Any,
        cull_threshold: Any,
        ambient_spacing_m: Any,
        ambient_samples: Any,
        layers: Any,
    ) -> _Options:
        """The options, each checked (TypeError or ValueError naming the parameter)."""
        if camera is not None and not isinstance(camera, Camera):
            raise TypeError(f"camera must be a skyfall.Camera, got {type(camera).__name__}")
        return cls(
            camera=camera,
            seed=integer("seed", seed, 0, 2**64 - 1),
            cull_threshold=None if cull_threshold is None else in_range("cull_threshold", cull_threshold),
            ambient_spacing_m=in_range("ambient_spacing_m", ambient_spacing_m),
            ambient_samples=integer("ambient_samples", ambient_samples, 4, 65_536),
            layers=_layer_names(layers),
        )


def _layer_names(layers: Any) -> tuple[str, ...] | None:
    """``layers`` (names, or a dict keyed by them) as a tuple of layer names in the order
    given, duplicates dropped; None stays None. ValueError names the valid layers."""
    if layers is None:
        return None
    if isinstance(layers, (str, bytes)) or not isinstance(layers, Iterable):
        raise TypeError(f"layers must be a sequence of layer names, such as ('rain_alpha',), or a dict of them to arrays; got {type(layers).__name__}")
    names = tuple(dict.fromkeys(layers))
    for name in names:
        if not isinstance(name, str):
            raise TypeError(f"layers must hold layer names (str), got {type(name).__name__}")
        if name not in _core.LAYERS:
            raise ValueError(f"layers: {name!r} is not a layer; the layers are {', '.join(map(repr, _core.LAYERS))}")
    return names


def _deprecated_outs(rain_alpha_out: Any, snow_alpha_out: Any, layers: Any) -> dict[str, Any] | None:
    """The arrays given the deprecated way (``rain_alpha_out``, ``snow_alpha_out``) as a
    ``layers`` dict, warning the caller's line (an entry point's own call); None if none."""
    given = {name: a for name, a in (("rain_alpha", rain_alpha_out), ("snow_alpha", snow_alpha_out)) if a is not None}
    if not given:
        return None
    keywords = " and ".join(f"{name}_out=" for name in given)
    warnings.warn(
        f"{keywords} deprecated: ask for the layers, layers={{{', '.join(f'{n!r}: array' for n in given)}}} fills "
        f"the arrays (layers={tuple(given)!r} returns new ones), and the call returns (image, layers)",
        DeprecationWarning,
        stacklevel=3,
    )
    if layers is not None:
        raise ValueError(f"give the layers once: layers= or the deprecated {keywords}, not both")
    return given


def _neutral(name: str, shape: tuple[int, ...], into: NDArray[np.float32] | None) -> NDArray[np.float32]:
    """Layer ``name``'s neutral value everywhere (``_core.LAYER_NEUTRAL``): written into
    ``into`` (an ``out`` frame's array for it) when given, else a new array."""
    value = np.float32(_core.LAYER_NEUTRAL[name])
    if into is None:
        return np.full(shape, value, np.float32)
    into[...] = value
    return into


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
        Ground-truth layers: the haze pass adds ``transmittance`` (e^(-sigma d), sigma at 550 nm:
        the green channel's; under a sky with a sun a box scene's clear air dims red less and
        blue more, at their own wavelengths); rain adds
        ``rain_alpha`` (streak coverage 1 - prod(1 - a_i)) and ``rain_depth_m`` (depth of the
        nearest visible streak, inf where none); a snow cover (``Weather(snow_cover=...)``) adds
        ``snow_depth_m`` (the depth of snow each pixel shows, 0 where none: thin snow's
        patches d / c(d) deep and the ground between them 0, their mean d far away); clouds
        (``Weather(clouds=...)``) add ``cloud_alpha`` (their coverage 1 - prod(1 - alpha_i)); a
        sky with a sun adds ``sun_transmittance`` on box scenes (the share of the sun's direct
        light reaching each pixel's surface: 0 behind a box, the clouds' Gamma elsewhere, 1 for
        sky): only the layers this frame's passes drew, or with ``layers=`` (:meth:`Renderer.render`)
        exactly the layers asked for, each neutral where no pass drew it.
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
        no Vulkan adapter exists, with what to install, and would refuse by name a frame with
        a stage the GPU does not draw (the core's plan; today it draws every stage);
        ``"auto"`` draws such a frame on the CPU.

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
        self._auto = backend == "auto"

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
        layers: Sequence[str] | None = None,
        out: Frame | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Frame:
        """Render one frame.

        Parameters
        ----------
        scene : BoxScene or PhotoScene
            What to show. A photo's size must equal the renderer's.
        weather : Weather, optional
            Default: clear (no rain, infinite visibility): the scene unchanged. Every effect
            (rain, snow, clouds, a windshield, a snow cover) is configured in it.
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
        layers : sequence of str, optional
            The ground-truth layers the frame carries, by name (:data:`skyfall._core.LAYERS`):
            ``frame.layers`` then holds exactly these, in this order, each a float32 (H, W)
            array, with its neutral value (``_core.LAYER_NEUTRAL``) where no pass drew it.
            None (default): the layers this frame's passes drew.
        out : Frame, optional
            A previous frame of this size to render into: its arrays are overwritten and come
            back in the new frame (layers this frame does not draw are left out of it, unless
            ``layers`` asks for them; layers it draws that ``out`` lacks are new arrays). Fresh
            arrays cost the kernel's zeroing of every page (58 MB per 1080p frame with its
            layers); reusing them saves that.
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.

        Returns
        -------
        Frame

        Raises
        ------
        ValueError
            For a value outside its range, a photo of another size, or a name in ``layers``
            that is not a layer (the message lists the layers).
        TypeError
            For an argument of the wrong type.
        """
        weather = _with_cover(weather, snow_cover)
        options = _Options.checked(camera, seed, cull_threshold, ambient_spacing_m, ambient_samples, layers)
        return self._render(scene, weather, options, time_s, out)

    def _render(self, scene: BoxScene | PhotoScene, weather: Weather, options: _Options, time_s: float, out: Frame | None) -> Frame:
        """:meth:`render` with its options checked: one core call."""
        request = self._request(scene, weather, options, time_s)
        arrays = self._out_arrays(out) if out is not None else None
        # One core call: the core derives the sky, the haze and its airlight, the rain and its
        # light from the request, draws every stage (the windshield last), and names the layers
        # it drew (skyfall._core.LAYERS).
        rgb, depth, drawn, stats = _core.render_frame(request, device=self._device, cpu_fallback=self._auto, out=arrays)
        if options.layers is not None:
            reuse = out.layers if out is not None else {}
            drawn = {name: drawn[name] if name in drawn else _neutral(name, depth.shape, reuse.get(name)) for name in options.layers}
        return Frame(
            rgb=rgb,
            depth_m=depth,
            layers=drawn,
            backend=self.backend,
            adapter_info=self.adapter_info,
            luminance_scale_cd_m2=weather.luminance_scale_cd_m2,
            stats=stats,
        )

    def fuses_srgb8(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        snow_cover: SnowCover | None = None,
        *,
        layers: Sequence[str] | Mapping[str, Any] | None = None,
    ) -> bool:
        """Whether :meth:`render_srgb8` of these takes the fused 8-bit path:
        ``srgb8_path(...) == "fused"`` (see :meth:`srgb8_path`).

        Parameters
        ----------
        scene : BoxScene or PhotoScene
            The scene.
        weather : Weather, optional
            The weather (its ``windshield``, ``clouds`` and ``snow_cover``).
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.
        layers : sequence of str or dict, optional
            The layers the call asks for (``render_srgb8``'s ``layers``).

        Returns
        -------
        bool
        """
        return self.srgb8_path(scene, _with_cover(weather, snow_cover), layers=layers) == "fused"

    def srgb8_path(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather | None = None,
        *,
        layers: Sequence[str] | Mapping[str, Any] | None = None,
    ) -> str:
        """Which path :meth:`render_srgb8` of these takes; every path gives the float frame's
        bytes within 1 code (``"banded"`` and ``"float"``: exactly).

        - ``"fused"``: an 8-bit photo on the CPU backend whose every stage the core declares
          the fused output draws (not a windshield, clouds, a snow cover or wet surfaces:
          ``_core.frame_plan`` lists a frame's stages), and no layer asked for but
          ``rain_alpha`` and ``snow_alpha``: each pixel decoded, hazed, composited and encoded
          once (the fastest);
        - ``"banded"``: on the CPU backend, anything else (box scenes and their glows, clouds,
          a snow cover, a windshield, any layer), in one core call: the frame's stages band by
          band, each band encoded as it is finished, with no frame-sized float buffer (with a
          windshield, whose drops refract other rows, the float frame is drawn first, then the
          glass, then the encoding);
        - ``"float"``: the GPU backend: the float frame rendered, then encoded.

        Parameters
        ----------
        scene : BoxScene or PhotoScene
            The scene.
        weather : Weather, optional
            The weather (its ``windshield``, ``clouds`` and ``snow_cover``).
        layers : sequence of str or dict, optional
            The layers the call asks for (``render_srgb8``'s ``layers``).

        Returns
        -------
        str
            ``"fused"``, ``"banded"`` or ``"float"``.

        Examples
        --------
        >>> import numpy as np
        >>> from skyfall import PhotoScene, Weather, scenes
        >>> r = Renderer(32, 24, backend="cpu")
        >>> photo = PhotoScene(np.full((24, 32, 3), 120, np.uint8), depth_m=np.full((24, 32), 30.0, np.float32))
        >>> r.srgb8_path(photo, Weather(rain_rate_mm_h=5.0)), r.srgb8_path(scenes.street(), Weather())
        ('fused', 'banded')
        """
        weather = weather if weather is not None else Weather()
        if self._device is not None:
            return "float"
        if not isinstance(scene, PhotoScene) or scene.srgb8 is None:
            return "banded"  # (without the request: a box scene's would build its ambient map)
        # Fused when every stage is one the core declares the fused output draws
        # (``_core.frame_plan``, the one place that decides it) and no layer is asked for but
        # FUSED_LAYERS.
        request = self._request(scene, weather)
        fused = set(_layer_names(layers) or ()) <= set(FUSED_LAYERS) and all(srgb8 for _, srgb8, _, _ in _core.frame_plan(request))
        return "fused" if fused else "banded"

    @overload
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
        layers: None = None,
        out: NDArray[np.uint8] | None = None,
        rain_alpha_out: NDArray[np.float32] | None = None,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> NDArray[np.uint8]: ...

    @overload
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
        layers: Sequence[str] | Mapping[str, NDArray[np.float32]],
        out: NDArray[np.uint8] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Srgb8Frame: ...

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
        layers: Sequence[str] | Mapping[str, NDArray[np.float32]] | None = None,
        out: NDArray[np.uint8] | None = None,
        rain_alpha_out: NDArray[np.float32] | None = None,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> NDArray[np.uint8] | Srgb8Frame:
        """Render one frame straight to 8-bit sRGB: the augmentation path.

        The same frame as :meth:`render` followed by :func:`skyfall.io.to_srgb8`, every byte
        within 1 code of it (nearly all equal). For an 8-bit :class:`PhotoScene` on the CPU
        backend the haze and the rain are fused into one pass over bands of rows that decodes,
        hazes, composites and encodes each pixel once, with no frame-sized float buffers: the
        fast way to put rain on a dataset of photos. Other scenes, clouds, a snow cover and
        layers other than ``rain_alpha`` and ``snow_alpha`` are drawn band by band, each band
        encoded as it is finished (the float frame's bytes, with no frame-sized float buffer;
        a windshield's frame is drawn whole before its glass, then encoded, in the same core
        call); the GPU backend renders the float frame and encodes it (:meth:`srgb8_path` says
        which path a call takes).

        Parameters
        ----------
        scene, weather, camera, time_s, seed, cull_threshold, ambient_spacing_m, ambient_samples
            As for :meth:`render`.
        layers : sequence of str, or dict of str to ndarray, optional
            The ground-truth layers to return with the image, by name
            (:data:`skyfall._core.LAYERS`), each a float32 (H, W) array with its neutral value
            where no pass drew it (``rain_alpha`` is the ground truth of a deraining
            dataset). A dict names the arrays to fill (writable, C-contiguous float32 of shape
            (H, W)): reusing them across frames saves their allocation. When given, the call
            returns a :class:`Srgb8Frame` (image, layers) instead of the image alone.
        out : ndarray of uint8, shape (H, W, 3), optional
            Where to write the image (C-contiguous); a new array when None. Reusing one
            across frames saves its allocation.
        rain_alpha_out, snow_alpha_out : ndarray of float32, shape (H, W), optional
            Deprecated (they warn): ``layers={"rain_alpha": array}`` fills the same arrays.
            Filled with the rain's (the snowflakes') coverage; the call still returns the
            image alone.
        snow_cover : SnowCover, optional
            Deprecated (it warns): the cover is part of the weather, ``Weather(snow_cover=...)``.

        Raises
        ------
        ValueError
            When a photo is not the renderer's size (checked first), when ``out`` or a layer's
            array has the wrong dtype, shape or layout, or overlaps the scene's photo, its
            depth map or another output, or when ``layers`` names a layer that does not exist
            (the message lists them).
        TypeError
            When ``out`` or a layer's array is not a numpy array.

        Returns
        -------
        ndarray of uint8, shape (H, W, 3), or Srgb8Frame
            The image (``out`` when given); with ``layers``, the image and the layers.

        Examples
        --------
        >>> from skyfall import Weather, scenes
        >>> image, layers = Renderer(32, 18, backend="cpu").render_srgb8(
        ...     scenes.street(), Weather(rain_rate_mm_h=10.0), layers=("rain_alpha", "snow_alpha"))
        >>> image.shape, sorted(layers), float(layers["snow_alpha"].max())
        ((18, 32, 3), ['rain_alpha', 'snow_alpha'], 0.0)
        """
        weather = _with_cover(weather, snow_cover)
        fills = _deprecated_outs(rain_alpha_out, snow_alpha_out, layers)
        options = _Options.checked(camera, seed, cull_threshold, ambient_spacing_m, ambient_samples, fills if fills is not None else layers)
        targets = self._srgb8_targets(scene, out, fills if fills is not None else layers, deprecated=fills is not None)
        image, filled = self._srgb8(scene, weather, options, time_s, out, targets)
        return image if layers is None else Srgb8Frame(image, filled)

    def _srgb8(
        self,
        scene: BoxScene | PhotoScene,
        weather: Weather,
        options: _Options,
        time_s: float,
        out: NDArray[np.uint8] | None,
        targets: dict[str, NDArray[np.float32] | None],
    ) -> tuple[NDArray[np.uint8], dict[str, NDArray[np.float32]]]:
        """:meth:`render_srgb8` with its options and outputs checked: the image and each
        target layer (its given array filled, or a new one)."""
        image = out if out is not None else np.empty((self.height, self.width, 3), np.uint8)
        request = self._request(scene, weather, options, time_s) if self._device is None else None
        # An 8-bit photo asking only for the fused path's layers goes to _core.render_photo8,
        # which reads the frame's plan itself and draws it fused, or banded when a stage needs
        # it (one core call either way; srgb8_path asks the same plan).
        fusable = isinstance(scene, PhotoScene) and scene.srgb8 is not None and set(targets) <= set(FUSED_LAYERS)
        path = "float" if request is None else "fused" if fusable else "banded"
        if path == "fused":
            assert isinstance(scene, PhotoScene) and scene.srgb8 is not None and request is not None
            filled = {name: a if a is not None else np.empty((self.height, self.width), np.float32) for name, a in targets.items()}
            _core.render_photo8(
                request, scene.srgb8, io.srgb8_table(), image, rain_alpha_out=filled.get("rain_alpha"), snow_alpha_out=filled.get("snow_alpha")
            )
            return image, filled
        if path == "banded":
            filled = {name: a if a is not None else np.empty((self.height, self.width), np.float32) for name, a in targets.items()}
            # A stage the fused path does not draw (clouds, a snow cover, a box scene and its
            # glows, a windshield) or a layer it does not fill: the stages band by band, each band encoded as
            # it is finished (the float frame's bytes, no frame-sized float buffer).
            assert request is not None
            _core.render_frame8(request, image, layers=filled)
            return image, filled
        # The GPU backend: float, then encode.
        frame = self._render(scene, weather, dataclasses.replace(options, layers=tuple(targets)), time_s, None)
        image[...] = io.to_srgb8(frame.rgb)
        filled = {}
        for name, a in targets.items():
            if a is None:
                filled[name] = frame.layers[name]
            else:
                a[...] = frame.layers[name]
                filled[name] = a
        return image, filled

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

    def _srgb8_targets(
        self, scene: Any, out: Any, layers: Sequence[str] | Mapping[str, Any] | None, *, deprecated: bool = False
    ) -> dict[str, NDArray[np.float32] | None]:
        """render_srgb8's outputs, checked after the photo's size (their shapes follow from it):
        each asked layer's array to fill (None: a new one). ``deprecated``: the arrays came as
        ``rain_alpha_out`` / ``snow_alpha_out`` and messages name them so."""
        self._check_photo_size(scene)
        names = _layer_names(layers) or ()
        given: Mapping[str, Any] = layers if isinstance(layers, Mapping) else {}

        def label(name: str) -> str:
            return f"{name}_out" if deprecated else f"layers[{name!r}]"

        shape = (self.height, self.width)
        if out is not None:
            _check_writable("out", out, np.uint8, (*shape, 3))
        targets: dict[str, NDArray[np.float32] | None] = {}
        for name in names:
            a = given.get(name)
            if a is not None:
                _check_writable(label(name), a, np.float32, shape)
            targets[name] = a
        _check_apart(scene, {"out": out, **{label(name): a for name, a in targets.items()}})
        return targets

    def _check_photo_size(self, scene: Any) -> None:
        """A photo must be the renderer's size (a box scene is rendered at any size)."""
        if isinstance(scene, PhotoScene) and scene.shape != (self.height, self.width):
            h, w = scene.shape
            raise ValueError(
                f"the photo is {w}x{h} px, the renderer {self.width}x{self.height} px: "
                f"render it with a renderer of its size, Renderer({w}, {h})"
            )

    def _request(self, scene: BoxScene | PhotoScene, weather: Weather, options: _Options | None = None, time_s: float = 0.0) -> _Request:
        """The frame's request for ``_core.render_frame`` and ``_core.render_photo8``: the
        frame's own objects (the core reads them attribute by attribute), with the scene's
        ambient-light map (built once per scene, sky and spacing, and cached). ``options``
        None: the entry points' defaults."""
        if not isinstance(weather, Weather):
            raise TypeError(f"weather must be a skyfall.Weather, got {type(weather).__name__}")
        opts = options if options is not None else _Options()
        t = in_range("time_s", time_s)
        if isinstance(scene, PhotoScene):
            self._check_photo_size(scene)
            cam = scene.camera
        elif isinstance(scene, BoxScene):
            cam = (opts.camera if opts.camera is not None else scene.camera).with_resolution(self.width, self.height)
        else:
            raise TypeError(f"scene must be a BoxScene or PhotoScene, got {type(scene).__name__}")
        field = in_sky = None
        if weather.clouds is not None:
            from skyfall import clouds as _clouds

            # Carried by the wind since time 0 (unchanged at time 0 or in still air).
            moving = _clouds.drifted(weather.clouds, weather.wind_m_s, t)
            field = _clouds.frame_field(moving, weather.sun_direction)
            # A rendered scene's sky light has the clouds in it (their drift in whole steps); a
            # photo keeps its own light.
            if isinstance(scene, BoxScene):
                in_sky = _clouds.sky_field(weather.clouds, weather.wind_m_s, t, weather.sun_direction)
        request: _Request = {
            "camera": cam,
            "weather": weather,
            "scene": scene,
            "time_s": t,
            "seed": opts.seed,
            "cull_threshold": opts.cull_threshold,
            "ambient": self._ambient(scene, weather, cam, opts.ambient_spacing_m, opts.ambient_samples, in_sky),
        }
        if field is not None:
            request["clouds"] = field
        if weather.snow_cover is not None:
            request["snow_cover"] = weather.snow_cover.core
        if weather.windshield is not None:
            from skyfall import windshield as _ws

            request["windshield"] = _ws.frame_glass(weather.windshield, opts.seed)
        return request

    @staticmethod
    def _ambient(
        scene: BoxScene | PhotoScene,
        weather: Weather,
        cam: Camera,
        spacing_m: float,
        samples: int,
        clouds: _core.CloudField | None = None,
    ) -> _core.AmbientLightMap:
        """The frame's ambient-light map (a single node of open sky where nothing hides it), cached;
        ``clouds`` in its sky when given."""
        s = in_range("ambient_spacing_m", spacing_m)
        n = integer("ambient_samples", samples, 4, 65_536)
        occluders = np.ascontiguousarray(scene.boxes if isinstance(scene, BoxScene) else scene.occluders, dtype=np.float32)
        if len(occluders) == 0:
            # The clouds seen from the ground below the camera, on the same 8 m steps as a box
            # scene's bounds (cameras a few metres apart share the map).
            step = sky.CAMERA_BOUNDS_STEP_M
            eye = np.round(np.asarray(cam.position_m, dtype=np.float64) / step) * step
            eye[1] = 0.0
            return sky.cached_core_map(occluders, weather, np.zeros(3), np.zeros(3), s, n, "ambient_spacing_m", clouds, eye)
        lo, hi = sky.default_bounds(scene, s, around_m=cam.position_m, radius_m=_particle_reach_m(weather))
        # The map spans the scene's boxes and the particles' regions around the camera: say so
        # in the user's terms when that cannot be built (the map's own message names its internals).
        limit = _core.AMBIENT_EXTENT_M
        if not (np.all(np.abs(lo) <= limit) and np.all(np.abs(hi) <= limit)):
            pos = ", ".join(f"{v:g}" for v in cam.position_m)
            raise ValueError(
                f"the camera at position_m = ({pos}) is too far from the scene's boxes: the ambient-light "
                f"map must span both, within [-{limit:g}, {limit:g}] m; put the camera near the boxes "
                "(a box scene's world is the boxes' own; far from the origin, use a PhotoScene)"
            )
        eye = 0.5 * (lo + hi)
        eye[1] = lo[1]
        return sky.cached_core_map(occluders, weather, lo, hi, s, n, "ambient_spacing_m", clouds, eye)

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
        layers: Sequence[str] | None = None,
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
        scene, weather, camera, seed, cull_threshold, ambient_spacing_m, ambient_samples, layers
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
        options = _Options.checked(camera, seed, cull_threshold, ambient_spacing_m, ambient_samples, layers)
        if out is not None:
            self._out_arrays(out)
        times = self._sequence_times(scene, weather, options, n_frames, fps, start_s, progress)

        def frames() -> Iterator[Frame]:
            into = out
            for t in times:
                frame = self._render(scene, weather, options, t, into)
                if out is not None:
                    into = frame  # out's arrays, and any layer the first frame added to them
                yield frame

        return frames()

    @overload
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
        layers: None = None,
        out: NDArray[np.uint8] | None = None,
        progress: bool = False,
        rain_alpha_out: NDArray[np.float32] | None = None,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Iterator[NDArray[np.uint8]]: ...

    @overload
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
        layers: Sequence[str] | Mapping[str, NDArray[np.float32]],
        out: NDArray[np.uint8] | None = None,
        progress: bool = False,
        snow_cover: SnowCover | None = None,
    ) -> Iterator[Srgb8Frame]: ...

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
        layers: Sequence[str] | Mapping[str, NDArray[np.float32]] | None = None,
        out: NDArray[np.uint8] | None = None,
        progress: bool = False,
        rain_alpha_out: NDArray[np.float32] | None = None,
        snow_alpha_out: NDArray[np.float32] | None = None,
        snow_cover: SnowCover | None = None,
    ) -> Iterator[NDArray[np.uint8]] | Iterator[Srgb8Frame]:
        """:meth:`render_sequence` in 8-bit sRGB: each frame is :meth:`render_srgb8` at
        ``time_s = start_s + k / fps``, byte for byte.

        Parameters
        ----------
        scene, weather, n_frames, fps, seed, camera, start_s, cull_threshold, ambient_spacing_m, ambient_samples, progress
            As for :meth:`render_sequence`.
        layers : sequence of str, or dict of str to ndarray, optional
            As for :meth:`render_srgb8`: each frame is then a :class:`Srgb8Frame`. A dict's
            arrays are filled anew for every frame (overwritten by the next); names alone give
            new arrays per frame.
        out : ndarray of uint8, shape (H, W, 3), optional
            Where to write every frame: each array yielded is then ``out``, overwritten by
            the next frame. None: a new array per frame.
        rain_alpha_out, snow_alpha_out, snow_cover
            Deprecated (they warn), as for :meth:`render_srgb8`.

        Returns
        -------
        iterator of ndarray of uint8, shape (H, W, 3), or of Srgb8Frame (with ``layers``)

        Raises
        ------
        ValueError, TypeError
            Every argument is checked when this is called, before the first frame (see
            :meth:`render_srgb8`).
        """
        weather = _with_cover(weather, snow_cover)
        fills = _deprecated_outs(rain_alpha_out, snow_alpha_out, layers)
        options = _Options.checked(camera, seed, cull_threshold, ambient_spacing_m, ambient_samples, fills if fills is not None else layers)
        targets = self._srgb8_targets(scene, out, fills if fills is not None else layers, deprecated=fills is not None)
        times = self._sequence_times(scene, weather, options, n_frames, fps, start_s, progress)

        def images() -> Iterator[NDArray[np.uint8]]:
            for t in times:
                yield self._srgb8(scene, weather, options, t, out, targets)[0]

        def frames() -> Iterator[Srgb8Frame]:
            for t in times:
                yield Srgb8Frame(*self._srgb8(scene, weather, options, t, out, targets))

        return images() if layers is None else frames()

    def _sequence_times(
        self, scene: BoxScene | PhotoScene, weather: Weather, options: _Options, n_frames: int, fps: float, start_s: float, progress: bool
    ) -> Iterator[float]:
        """A sequence's frame times (behind a progress bar, started at the first frame), with
        every argument checked now, as :meth:`render` checks them (the first frame's request)."""
        times = _frame_times(n_frames, fps, start_s)
        show = flag("progress", progress)
        self._request(scene, weather, options, times(0))
        return _progress(times, show)


def _particle_reach_m(weather: Weather) -> float:
    """How far from the camera the ambient-light map must reach, m: a metre beyond the
    farthest drawn particle (the rain's ``rain_near_m`` when its streaks are drawn, the
    snow's ``snow_near_m`` when it snows), and a metre around the camera without any."""
    reach = 1.0
    if weather.rain_rate_mm_h > 0 and weather.rain_streaks and weather.dry_s == 0:
        reach = max(reach, weather.rain_near_m + 1.0)
    if weather.snow_rate_mm_h > 0:
        reach = max(reach, weather.snow_near_m + 1.0)
    return reach


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
