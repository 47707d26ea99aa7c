"""Particle clouds lit by the sun (Shimada, Shinya, Shiraishi & Harada, "Fast rendering of
dynamic clouds using GPU shaders", IPSJ 2008, improving Harris & Lastra 2001).

A cloud is a set of Gaussian particles: particle i has its centre, its 1/e radius r_i
(density proportional to exp(-d^2 / r_i^2), cut at 2.5 radii), its optical depth tau_i
through the centre and its single-scattering albedo a_i. Sunlight crossing particle i keeps
the share G_i = exp(-(1 - a_i f) tau_i), f = g^2 the forward-peak share of the droplets'
scattering (delta-M scaling): the paper's G = a tau p(l, l) / 4 pi + exp(-tau) to first order
in tau, but never above 1.

- :func:`particles`: procedural, seeded clouds (cumulus, stratocumulus, a broken field).
- :func:`harris_illumination`: the light reaching each particle by Harris' sorted recurrence,
  the reference and the speed baseline.
- :func:`attenuation_volume`: the multiplicative attenuation volume Gamma of a light-aligned
  box, order-independent, with trilinear :meth:`AttenuationVolume.sample`.
- In frames: ``Weather(clouds=...)`` (a :class:`Cloud` or a name of :data:`PRESETS`) draws the
  clouds over the sky, lit per fragment from their volumes (:func:`frame_field`), and under a
  sky with a sun shades the ground (``layers["sun_transmittance"]``).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import all_in_range, choice, float_array, in_range, integer, integer_in_range

__all__ = [
    "DOME_FACE_PX",
    "FRAME_RESOLUTION",
    "KINDS",
    "PRESETS",
    "Part",
    "drifted",
    "frame_field",
    "preset",
    "SKY_DRIFT_STEP_M",
    "sky_dome",
    "sky_field",
    "AttenuationVolume",
    "Cloud",
    "attenuation_volume",
    "harris_illumination",
    "particles",
    "path_traced",
]

KINDS: Final = ("cumulus", "stratocumulus", "broken")
"""The kinds :func:`particles` makes."""

_DEFAULT_EXTENT_M: Final = {"cumulus": 1500.0, "stratocumulus": 4000.0, "broken": 4000.0}
_DEFAULT_G: Final = 0.8641  # Mie, r_eff 10 um at 550 nm (the reference table)


def _vector(name: str, value: Any) -> NDArray[np.float64]:
    a = all_in_range(name, value)
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got shape {a.shape}")
    return a


@dataclass(frozen=True, eq=False)
class Cloud:
    """A particle cloud.

    Parameters
    ----------
    positions_m : array_like, shape (N, 3)
        Particle centres, world metres (+Y up), each coordinate in [-1e7, 1e7] m.
    radii_m : array_like, shape (N,)
        Gaussian 1/e radii, m, each in (0, 100000] m.
    optical_depths : array_like, shape (N,)
        Extinction optical depths through the centres, each in [0, 10000].
    albedos : array_like, shape (N,)
        Single-scattering albedos, each in [0, 1].
    asymmetry_g : float
        Henyey-Greenstein asymmetry of the droplets, in [0, 0.99]; 0.8641 (Mie, r_eff 10 um,
        550 nm) by default.

    The arrays are stored as read-only C-contiguous float64 copies. ``N`` must be at least 1.
    """

    positions_m: NDArray[np.float64]
    radii_m: NDArray[np.float64]
    optical_depths: NDArray[np.float64]
    albedos: NDArray[np.float64]
    asymmetry_g: float = _DEFAULT_G

    def __post_init__(self) -> None:
        p = float_array("positions_m", self.positions_m)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"positions_m must have shape (N, 3), got {p.shape}")
        if p.shape[0] == 0:
            raise ValueError("positions_m: a cloud needs at least one particle, got 0")
        all_in_range("positions_m", p)
        arrays = {"positions_m": p}
        for name in ("radii_m", "optical_depths", "albedos"):
            a = _vector(name, getattr(self, name))
            if a.shape[0] != p.shape[0]:
                raise ValueError(f"{name} has length {a.shape[0]}, expected {p.shape[0]} (one per particle)")
            arrays[name] = a
        for name, a in arrays.items():
            c = np.array(a, dtype=np.float64, order="C")
            c.flags.writeable = False
            object.__setattr__(self, name, c)
        object.__setattr__(self, "asymmetry_g", in_range("asymmetry_g", self.asymmetry_g))

    @property
    def n_particles(self) -> int:
        """Number of particles N."""
        return int(self.positions_m.shape[0])

    def translated(self, offset_m: Any) -> Cloud:
        """The same cloud moved by ``offset_m`` (3 floats, m): wind carrying it, or placing
        it in a scene. Its frames' volumes are built anew (a new cloud).

        Parameters
        ----------
        offset_m : sequence of 3 float
            The displacement, world metres.

        Returns
        -------
        Cloud
        """
        v = float_array("offset_m", offset_m).reshape(-1)
        if v.shape != (3,):
            raise ValueError(f"offset_m must have 3 components, got shape {v.shape}")
        return Cloud(self.positions_m + v, self.radii_m, self.optical_depths, self.albedos, self.asymmetry_g)

    def _args(
        self,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
        return (self.positions_m, self.radii_m, self.optical_depths, self.albedos, self.asymmetry_g)


def particles(
    kind: str = "cumulus",
    *,
    n_particles: int = 20000,
    extent_m: float | None = None,
    altitude_m: float = 1500.0,
    seed: int = 0,
) -> Cloud:
    """A procedural, seeded cloud.

    A kind is a shape of billows (Rust: ``skyfall_core::cloud::billows``): root spheres per
    convective cell, each sphere carrying children of about half its radius on its upper
    surface for two or three levels (the cauliflower of a cumulus' turrets), the union cut
    flat at the base (the condensation level) and perturbed by value noise at the smallest
    billows' scale. ``"cumulus"``: one tower of four stacked turrets on three shoulders, about
    as tall as it is wide; ``"broken"``: fourteen small cumulus of two or three turrets each
    scattered over a square; ``"stratocumulus"``: a deck of cells on a jittered grid, a
    twentieth of its side thick (at most 400 m) and cut flat at its top too (the inversion),
    whose cells thin out towards the deck's edge so it ends in scattered cells, not a line.

    Particles are small at the surface and large inside: a point at depth D below the surface
    has the relative spacing g = min(1 + D / L, 4), L the smallest billows' mean radius.
    Positions are drawn uniformly in the box from a PCG64 stream seeded by ``(seed, kind)`` and
    kept inside the shape with probability g^-3 until ``n_particles`` are kept; each stands for
    the volume v_i = V g_i^3 / sum(g^3), V the cloud's volume (the share of draws inside).
    Radii are 2 v_i^(1/3) times a uniform [0.8, 1.2], and optical depths
    tau_i = beta v_i / (pi r_i^2) make the particles' sum carry the extinction beta of the
    kind's droplets everywhere inside (Mie at 550 nm; beta = 3 Q_ext LWC / (4 rho_w r_eff),
    Stephens 1978): cumulus r_eff 10 um, LWC 1 g/m^3 (beta 0.157 /m, g 0.864); stratocumulus
    5 um, 0.1 g/m^3 (0.032 /m, g 0.849); broken 15 um, 0.5 g/m^3 (0.052 /m, g 0.870). More
    particles make smaller ones at the surface, so sharper edges and finer billows: a 1500 m
    cumulus needs about 30 000 to show its turrets' turrets.

    Parameters
    ----------
    kind : {"cumulus", "stratocumulus", "broken"}
        The cloud's kind.
    n_particles : int
        Particles, in [1, 1000000].
    extent_m : float, optional
        Horizontal extent, m, in [10, 100000] m: the cumulus' width (1500 m by default), the
        side of the stratocumulus deck or the broken field (4000 m).
    altitude_m : float
        Altitude of the cloud's base above y = 0, m, in [0, 20000] m.
    seed : int
        Seed, in [0, 2^64).

    Returns
    -------
    Cloud
        Same arguments, same bits.
    """
    choice("kind", kind, KINDS)
    n = integer_in_range("n_particles", n_particles)
    extent = in_range("extent_m", _DEFAULT_EXTENT_M[kind] if extent_m is None else extent_m)
    altitude = in_range("altitude_m", altitude_m)
    s = integer_in_range("seed", seed)
    p, r, t, a, g = _core.cloud_particles(kind, n, extent, altitude, s)
    return Cloud(p, r, t, a, g)


def _cloud(cloud: Any) -> Cloud:
    if not isinstance(cloud, Cloud):
        raise TypeError(f"cloud must be a skyfall.clouds.Cloud, got {type(cloud).__name__}")
    return cloud


def _sun(sun_direction: Any) -> tuple[float, float, float]:
    v = float_array("sun_direction", sun_direction)
    if v.shape != (3,):
        raise ValueError(f"sun_direction must have 3 components, got shape {v.shape}")
    x, y, z = _core.check_sun_direction((float(v[0]), float(v[1]), float(v[2])))
    return (x, y, z)


def harris_illumination(cloud: Cloud, sun_direction: Any, *, sun_radiance: float = 1.0) -> NDArray[np.float64]:
    """Sunlight reaching each particle by Harris' sorted recurrence.

    The particles are sorted along the light, nearest the sun first; each reads the light its
    predecessors left at its centre, I_k = I_0 prod_{i<k} G_i(rho_ik), with
    G_i(rho) = exp(-(1 - a_i g^2) tau_i exp(-rho^2 / r_i^2)) at distance rho from particle
    i's axis along the light, then adds its own G for those after it. The predecessors'
    footprints are summed exactly (a grid of cells across the light finds them), so the
    reference has no pixel error; sums of log G keep dense clouds finite.

    Parameters
    ----------
    cloud : Cloud
        The cloud.
    sun_direction : array_like, shape (3,)
        Direction towards the sun (any non-zero length).
    sun_radiance : float
        Sunlight entering the cloud, in [0, 1e12]; the result is in its unit.

    Returns
    -------
    ndarray of float64, shape (N,)
        I_k per particle.
    """
    c = _cloud(cloud)
    sun = _sun(sun_direction)
    radiance = in_range("sun_radiance", sun_radiance)
    return _core.harris_illumination(*c._args(), sun, radiance)


@dataclass(frozen=True, eq=False)
class AttenuationVolume:
    """The share of sunlight Gamma left at each voxel of a light-aligned box.

    Attributes
    ----------
    gamma : ndarray of float32, shape (R, R, R)
        Gamma per voxel; axis 2 runs along the light's travel (away from the sun), axes 0 and
        1 across it. Voxel (i, j, k)'s centre is at t = ((i, j, k) + 0.5) / R.
    world_from_volume : ndarray of float64, shape (4, 4)
        Maps box coordinates t in [0, 1]^3 (homogeneous) to world metres; its first three
        columns are the box's orthogonal edges, the fourth its corner t = 0.
    sun_direction : ndarray of float64, shape (3,)
        The unit direction towards the sun it was built for.
    """

    gamma: NDArray[np.float32]
    world_from_volume: NDArray[np.float64]
    sun_direction: NDArray[np.float64]

    @property
    def resolution(self) -> int:
        """Voxels per side R."""
        return int(self.gamma.shape[0])

    def sample(self, points_m: Any) -> NDArray[np.float32]:
        """Trilinear Gamma at world points.

        Parameters
        ----------
        points_m : array_like, shape (..., 3)
            World points, m.

        Returns
        -------
        ndarray of float32, shape (...)
            Gamma; points outside the box read its nearest face (across the light about 1,
            beyond the cloud along the light its whole shadow).
        """
        p = float_array("points_m", points_m)
        if p.ndim == 0 or p.shape[-1] != 3:
            raise ValueError(f"points_m must have shape (..., 3), got {p.shape}")
        flat = np.ascontiguousarray(p.reshape(-1, 3))
        out = _core.sample_attenuation(self.gamma, self.world_from_volume, flat)
        return out.reshape(p.shape[:-1])


def attenuation_volume(cloud: Cloud, sun_direction: Any, *, resolution: int = 128) -> AttenuationVolume:
    """The multiplicative attenuation volume Gamma = exp(sum log G) of Shimada et al.

    Built order-independently: each particle adds its footprint log G_i(rho) at its own depth
    (half a slice behind its centre, shared linearly between two slices), and a prefix sum
    along the light carries it to every voxel behind; the cost grows as particles x footprint
    + voxels. The sums are fixed point (2^-28 in log Gamma), so shuffling the particles gives
    the same bits; work is split across the light over the thread pool.

    Parameters
    ----------
    cloud : Cloud
        The cloud.
    sun_direction : array_like, shape (3,)
        Direction towards the sun (any non-zero length).
    resolution : int
        Voxels per side R, in [2, 512].

    Returns
    -------
    AttenuationVolume
        Gamma (R, R, R) float32 and its box.
    """
    c = _cloud(cloud)
    sun = _sun(sun_direction)
    r = integer_in_range("resolution", resolution)
    gamma, world_from_volume = _core.attenuation_volume(*c._args(), sun, r)
    gamma.flags.writeable = False
    world_from_volume.flags.writeable = False
    direction = np.array(sun, dtype=np.float64)
    direction.flags.writeable = False
    return AttenuationVolume(gamma, world_from_volume, direction)


class Part(NamedTuple):
    """One part of a preset cloud: :func:`particles` arguments, where the cloud is moved to and
    the half-space it is kept in (particles with z below ``keep_z_below_m``)."""

    kind: str
    n_particles: int
    extent_m: float
    altitude_m: float
    offset_m: tuple[float, float, float]
    seed: int
    keep_z_below_m: float = math.inf


PRESETS: Final = {
    "broken": (
        Part("broken", 60000, 2000.0, 1000.0, (-400.0, 0.0, 425.0), 24),
        Part("cumulus", 12000, 1400.0, 1000.0, (-1200.0, 0.0, -3500.0), 10),
        Part("cumulus", 12000, 1600.0, 1000.0, (900.0, 0.0, -5000.0), 11),
        Part("cumulus", 12000, 2000.0, 1000.0, (-300.0, 0.0, -7500.0), 12),
        Part("cumulus", 12000, 1000.0, 1000.0, (2500.0, 0.0, -3000.0), 13),
    ),
    "cumulus": (Part("cumulus", 60000, 1500.0, 1200.0, (0.0, 0.0, -5000.0), 0),),
    "stratocumulus": (Part("stratocumulus", 60000, 24000.0, 1000.0, (0.0, 0.0, -8000.0), 0),),
}
"""The clouds ``Weather(clouds=name)`` draws: the parts' :func:`particles`, each of its kind and
seed, moved by ``offset_m`` so that a default camera (at the origin, looking along -Z) sees
them, bases at ``altitude_m``. ``"broken"``: a broken field 2 km across over the camera (its
shadows: under a sun 50 deg up in the south, azimuth 185, a cloud's shadow covers the near
half of the bundled street, :func:`skyfall.scenes.street`, and the far half lies in the sun) and four cumulus 1-2 km wide, 3-7.5 km ahead
(the clouds a camera looking along the street sees); ``"cumulus"``: one cumulus 1.5 km wide
5 km ahead; ``"stratocumulus"``: a deck 24 km across and 400 m thick, centred 8 km ahead, whose
cells thin out from 8 km beyond the camera onwards (no line where it ends). The parts' particle
counts (108 000, 60 000, 60 000) are what their billows need to show at 1280 x 720; fewer make
softer, blobbier clouds (see :func:`particles`)."""

FRAME_RESOLUTION: Final = 256
"""Voxels per side of the attenuation volumes frames light their clouds from."""


@lru_cache(maxsize=8)
def preset(name: str) -> Cloud:
    """The cloud of preset ``name`` (:data:`PRESETS`), made once per process.

    Parameters
    ----------
    name : str
        One of :data:`PRESETS`.

    Returns
    -------
    Cloud
    """
    choice("clouds", name, tuple(PRESETS))
    arrays: list[tuple[NDArray[np.float64], ...]] = []
    g = _DEFAULT_G
    for part in PRESETS[name]:
        c = particles(part.kind, n_particles=part.n_particles, extent_m=part.extent_m, altitude_m=part.altitude_m, seed=part.seed)
        p = c.positions_m + np.asarray(part.offset_m, dtype=np.float64)
        keep = p[:, 2] < part.keep_z_below_m
        arrays.append((p[keep], c.radii_m[keep], c.optical_depths[keep], c.albedos[keep]))
        g = c.asymmetry_g
    p, r, t, a = (np.concatenate([x[i] for x in arrays]) for i in range(4))
    return Cloud(p, r, t, a, g)


_FIELDS: weakref.WeakKeyDictionary[Cloud, dict[tuple[Any, int, bool], Any]] = weakref.WeakKeyDictionary()
_DRIFTED: weakref.WeakKeyDictionary[Cloud, tuple[tuple[float, float, float], Cloud]] = weakref.WeakKeyDictionary()


def drifted(clouds: Cloud | str, wind_m_s: Any, time_s: float) -> Cloud:
    """The clouds as the wind has carried them at ``time_s``: translated by the wind's
    horizontal components times the time, (wind_x t, 0, wind_z t) m (they neither rise nor
    sink). Frames call it with ``Weather.wind_m_s`` and the frame's ``time_s``, so clouds drift
    across the sky in :meth:`skyfall.Renderer.render_sequence`; at ``time_s = 0`` or in still
    air the cloud itself is returned, and its frames are unchanged.

    The drifted cloud's attenuation volumes are built anew (the last drift of each cloud is
    kept, so frames at one time share them).

    Parameters
    ----------
    clouds : Cloud or str
        A cloud, or a name of :data:`PRESETS`.
    wind_m_s : sequence of 3 float
        The wind, m/s (its vertical component is ignored).
    time_s : float
        Time since the clouds stood where ``clouds`` places them, s.

    Returns
    -------
    Cloud

    Examples
    --------
    >>> from skyfall import clouds
    >>> c = clouds.preset("cumulus")
    >>> moved = clouds.drifted(c, (10.0, 0.0, 0.0), 6.0)
    >>> float((moved.positions_m - c.positions_m)[0, 0])
    60.0
    >>> clouds.drifted(c, (10.0, 0.0, 0.0), 0.0) is c
    True
    """
    cloud = preset(clouds) if isinstance(clouds, str) else _cloud(clouds)
    return _moved(cloud, _offset(wind_m_s, time_s), _DRIFTED)


SKY_DRIFT_STEP_M: Final = 25.0
"""In a box scene's sky light (its ambient-light map) the clouds move in steps of this much
drift, m: :func:`sky_field`. 25 m is under a degree for clouds a couple of kilometres away,
below the dome's 2.8 deg pixels, and the map's light changes by well under 1 % a step."""
_SKY_DRIFTED: weakref.WeakKeyDictionary[Cloud, tuple[tuple[float, float, float], Cloud]] = weakref.WeakKeyDictionary()


def _offset(wind_m_s: Any, time_s: float) -> tuple[float, float, float]:
    """The wind's drift by ``time_s``: (wind_x t, 0, wind_z t) m, checked."""
    w = float_array("wind_m_s", wind_m_s).reshape(-1)
    if w.shape != (3,):
        raise ValueError(f"wind_m_s must have 3 components, got shape {w.shape}")
    t = in_range("time_s", time_s)
    return (float(w[0]) * t, 0.0, float(w[2]) * t)


def _moved(cloud: Cloud, offset: tuple[float, float, float], last_of: weakref.WeakKeyDictionary[Cloud, tuple[tuple[float, float, float], Cloud]]) -> Cloud:
    """``cloud`` translated by ``offset`` (itself for none), the last one kept per cloud in ``last_of``."""
    if offset[0] == 0.0 and offset[2] == 0.0:
        return cloud
    last = last_of.get(cloud)
    if last is not None and last[0] == offset:
        return last[1]
    moved = cloud.translated(offset)
    last_of[cloud] = (offset, moved)
    return moved


def sky_field(clouds: Cloud | str, wind_m_s: Any, time_s: float, sun_direction: tuple[float, float, float] | None) -> Any:
    """The clouds a box scene's sky light draws at ``time_s``: their drift rounded to
    :data:`SKY_DRIFT_STEP_M` per axis, made ready for frames (:func:`frame_field`). In still air,
    or at a whole step, the frame's own field; a clip in wind builds one more field (and the
    sky light's dome and map) per step instead of per frame. Deterministic: the rounding depends
    on the time alone."""
    cloud = preset(clouds) if isinstance(clouds, str) else _cloud(clouds)
    x, _, z = _offset(wind_m_s, time_s)
    step = SKY_DRIFT_STEP_M
    offset = (round(x / step) * step, 0.0, round(z / step) * step)
    return frame_field(_moved(cloud, offset, _SKY_DRIFTED), sun_direction)


def frame_field(clouds: Cloud | str, sun_direction: tuple[float, float, float] | None, resolution: int = FRAME_RESOLUTION, *, diffuse: bool = True) -> Any:
    """The clouds made ready for frames under a sun (``_core.CloudField``): their
    attenuation volumes for the sun and for the zenith at ``resolution``^3, built once per
    cloud, sun and resolution and cached while the cloud lives.

    Parameters
    ----------
    clouds : Cloud or str
        A cloud, or a name of :data:`PRESETS`.
    sun_direction : tuple of 3 float or None
        Towards the sun (``Weather.sun_direction``); None: no sun.
    resolution : int
        Voxels per side, in [2, 1024].
    diffuse : bool
        Light the fragments with the diffuse term (the approximation of multiple scattering,
        see the README) besides the sun's single scattering: True in frames; False measures
        single scattering alone.

    Returns
    -------
    skyfall._core.CloudField
    """
    cloud = preset(clouds) if isinstance(clouds, str) else _cloud(clouds)
    n = integer_in_range("resolution", resolution)
    sun3 = None if sun_direction is None else (float(sun_direction[0]), float(sun_direction[1]), float(sun_direction[2]))
    key = (sun3, n, bool(diffuse))
    cache = _FIELDS.setdefault(cloud, {})
    field = cache.get(key)
    if field is None:
        field = _core.CloudField(*cloud._args(), sun3, n, diffuse=bool(diffuse))
        cache[key] = field
    return field


DOME_FACE_PX: Final = _core.CLOUD_DOME_FACE_PX
"""Pixels along a side of the dome's faces (``_core.CloudDome``): about 2.8 deg a pixel. The light
the presets' skies give the open ground is within 0.5 % of 128 px faces'
(``benches/results/cloud_sky_light.md``)."""


def sky_dome(weather: Any, eye_m: Any = (0.0, 0.0, 0.0), *, time_s: float = 0.0, face_px: int = DOME_FACE_PX) -> Any:
    """The weather's clouds as the sky's light sees them from a point (``_core.CloudDome``).

    The clouds (``weather.clouds``, drifted to ``time_s`` by ``weather.wind_m_s`` in steps of
    :data:`SKY_DRIFT_STEP_M`, as frames' sky light draws them) drawn by the
    frames' cloud pass on the five upward faces of a cube around ``eye_m``: along each
    direction above the horizon, the share of the sky behind them that gets through (T) and the
    light they send towards the point (S, linear RGB in the frames' relative units: a white
    surface under the open sky is 1). A box scene's ambient-light map integrates the sky with
    them in it, tau (L_sky T + S) + A (1 - tau) along each direction (tau and A the haze below
    the cloud base), so the clouds dim or brighten the sky light on every surface and, through
    the map's light at the camera, the haze's airlight. Frames build it themselves, seen from
    the middle of the map on the ground; this function shows what they see.

    Parameters
    ----------
    weather : skyfall.Weather
        A weather with ``clouds``.
    eye_m : sequence of 3 float
        The point, m.
    time_s : float
        The frame's time, s (the clouds' drift).
    face_px : int
        Pixels along a face's side, in [4, 1024].

    Returns
    -------
    skyfall._core.CloudDome
        ``sample(dirs)`` (unit directions, (N, 3) float64) gives T (N,) and S (N, 3).

    Examples
    --------
    >>> import numpy as np
    >>> from skyfall import Weather, clouds
    >>> w = Weather(sky=12, sun_elevation_deg=50.0, sun_azimuth_deg=185.0, clouds="stratocumulus")
    >>> t, s = clouds.sky_dome(w).sample(np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]))
    >>> bool(t[0] < 1.0), float(t[1])  # the deck overhead; nothing below the horizon
    (True, 1.0)
    """
    if weather.clouds is None:
        raise ValueError("weather.clouds is None: a dome needs clouds (a Cloud or a preset's name)")
    field = sky_field(weather.clouds, weather.wind_m_s, time_s, weather.sun_direction)
    return _dome_of(field, weather, eye_m, face_px)


def _dome_of(field: Any, weather: Any, eye_m: Any, face_px: int = DOME_FACE_PX) -> Any:
    """``_core.CloudDome`` of a frame field (``frame_field``) under ``weather``'s sky and sun, seen
    from ``eye_m``: what :func:`sky_dome` and the renderer's ambient-light maps build."""
    eye = float_array("eye_m", eye_m).reshape(-1)
    if eye.shape != (3,):
        raise ValueError(f"eye_m must have 3 components, got shape {eye.shape}")
    n = integer("face_px", face_px, 4, 1024)
    return _core.CloudDome(field, weather.sky_model(), (float(eye[0]), float(eye[1]), float(eye[2])), weather.sun_relative, n)


def path_traced(
    cloud: Cloud,
    sun_direction: Any,
    *,
    sun_relative: float,
    eye_m: Any,
    directions: Any,
    paths: int = 256,
    max_orders: int = 256,
    seed: int = 0,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The reference for clouds' light: a brute-force Monte Carlo path tracer of ``cloud``
    under the sun, every order of scattering, a black sky.

    The medium is the cloud's own Gaussian density (each particle's column through its centre
    is its optical depth, its albedo weighs its share, Henyey-Greenstein with the cloud's g);
    free flights are sampled exactly by inverting the analytic optical depth along each ray,
    and each vertex adds the sun's light through the exact transmittance (next-event
    estimation). Results are in frames' relative units (pi L / E, the sun's normal
    illuminance ``sun_relative`` times E).

    Parameters
    ----------
    cloud : Cloud
        The cloud.
    sun_direction : sequence of 3 float
        Towards the sun.
    sun_relative : float
        The sun's normal illuminance over E, at least 0 (``Weather.sun_relative``).
    eye_m : sequence of 3 float
        Where the paths start, world metres.
    directions : array_like, shape (N, 3)
        The view directions (normalised here).
    paths : int
        Paths per direction, at least 1.
    max_orders : int
        Scattering vertices per path at most, at least 1.
    seed : int
        Seed, in [0, 2^64): direction k's paths are seeded by (seed, k).

    Returns
    -------
    radiance, single, std_err : ndarray, shape (N,)
        Every order; single scattering alone; one standard error of ``radiance``.
    """
    c = _cloud(cloud)
    sun = _sun(sun_direction)
    eye = float_array("eye_m", eye_m).reshape(-1)
    if eye.shape != (3,):
        raise ValueError(f"eye_m must have 3 components, got shape {eye.shape}")
    d = np.ascontiguousarray(float_array("directions", directions), dtype=np.float64)
    if d.ndim != 2 or d.shape[1] != 3:
        raise ValueError(f"directions must have shape (N, 3), got {d.shape}")
    n_paths = integer("paths", paths, 1, 1 << 24)
    orders = integer("max_orders", max_orders, 1, 1 << 16)
    s = integer_in_range("seed", seed)
    return _core.cloud_path_traced(*c._args(), sun, float(sun_relative), (float(eye[0]), float(eye[1]), float(eye[2])), d, n_paths, orders, s)
