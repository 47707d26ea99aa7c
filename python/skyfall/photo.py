"""What a photo says about its own light and geometry: its airlight, and a depth map when it
comes without one.

A :class:`skyfall.PhotoScene` uses both by default. The airlight is the radiance the rain and
mist of a frame tend to with distance (and a sky pixel at the horizon); putting it in the
photo's own units and colour keeps a dusk photo dusky and a bright one bright, and scales the
rain's light with it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall import _core
from skyfall._validate import in_range, integer
from skyfall.camera import Camera
from skyfall.io import decode_srgb8
from skyfall.sky_mask import estimate_sky_mask

__all__ = [
    "HORIZON_FRACTION",
    "NEUTRAL_GUARD",
    "PATCH_PX",
    "TOP_FRACTION",
    "assumed_depth",
    "dark_channel",
    "estimate_airlight",
    "estimate_sky_mask",
    "exif_vertical_fov_deg",
    "fill_depth_holes",
    "ground_plane_depth",
    "level_camera",
    "sky_level_camera",
]

PATCH_PX: int = _core.AIRLIGHT_PATCH_PX
"""He, Sun & Tang's patch side, px (15)."""
TOP_FRACTION: float = _core.AIRLIGHT_TOP_FRACTION
"""The brightest share of the dark channel taken as haze-opaque (0.001)."""
HORIZON_FRACTION = 0.1
"""The share of a photo's sky pixels, lowest first, whose median is its horizon sky."""
NEUTRAL_GUARD = 0.5
"""The largest saturation, (max - min)/max of its linear channels, that He, Sun & Tang's
atmospheric light may have in a photo without sky; a more colourful one is a surface (a brown
table, an orange wall), and the airlight is then the neutral grey of its luminance."""


def _image(image: Any) -> NDArray[Any]:
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = a.astype(np.float32, copy=False)
        if not np.all(np.isfinite(a)):
            raise ValueError("image must hold finite values")
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"image must have shape (H, W, 3), got {a.shape}")
    return np.ascontiguousarray(a)


def dark_channel(image: Any, *, patch_px: int = PATCH_PX) -> NDArray[np.float32]:
    """The dark channel of He, Sun & Tang, "Single image haze removal using dark channel
    prior" (CVPR 2009): each pixel's smallest channel over the square window around it.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        uint8 codes or float values (any monotonic encoding: the result is in its values).
    patch_px : int
        Window side, px, odd, in [1, 1001]; the window is cut at the image's borders.

    Returns
    -------
    ndarray of float32, shape (H, W)
    """
    return _core.dark_channel(_image(image), integer("patch_px", patch_px, 1, 1001))


def estimate_airlight(
    image: Any,
    *,
    depth_m: Any = None,
    camera: Camera | None = None,
    patch_px: int = PATCH_PX,
    top_fraction: float = TOP_FRACTION,
) -> NDArray[np.float32]:
    """A photo's airlight, linear RGB in its own units: its horizon sky, or He, Sun & Tang's
    atmospheric light, guarded to a neutral grey, where it shows no sky.

    With a depth map that marks sky (``inf``) and the camera: the per-channel median of the
    sky pixels at the lowest :data:`HORIZON_FRACTION` of their elevations (on every k-th row
    and column, at most about 2^16 pixels: k = 6 at 1920 x 1080), the horizon sky the
    haze of a rainy frame tends to (a median, so a lamp, a white tower or the sun there does
    not set it). Without sky pixels: among the brightest ``top_fraction`` of the dark channel
    (the haze-opaque parts of a hazy photo), the pixel whose channels sum highest (He, Sun &
    Tang, "Single image haze removal using dark channel prior", CVPR 2009), kept only while its
    saturation is at most :data:`NEUTRAL_GUARD` (mist and rain light are near grey); a more
    colourful pick is a surface in a clear photo (the coffee table's brown), and the airlight is
    then the neutral grey of the pick's luminance (Rec. 709 weights), so rain and mist never take
    a foreground's colour. Give the airlight yourself where you know it
    (``PhotoScene(airlight=...)``).

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        uint8 sRGB codes (decoded with the sRGB transfer function) or float32 linear light.
    depth_m : array_like, shape (H, W), optional
        The photo's depth, ``inf`` for sky.
    camera : Camera, optional
        The camera that took it, with its resolution (needed with ``depth_m``).
    patch_px : int
        Dark-channel window side, px, odd, in [1, 1001] (default 15, as He, Sun & Tang).
    top_fraction : float
        Share of the dark channel searched, in (0, 1] (default 0.001).

    Returns
    -------
    ndarray of float32, shape (3,)
        Linear RGB.

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((40, 40, 3), np.float32)
    >>> img[:10] = (0.5, 0.6, 0.7)  # a pale sky band over a black ground
    >>> estimate_airlight(img).tolist()
    [0.5, 0.6000000238418579, 0.699999988079071]
    >>> img[:10] = (0.6, 0.3, 0.1)  # a brown table is no airlight: its grey instead
    >>> [round(v, 4) for v in estimate_airlight(img).tolist()]
    [0.3493, 0.3493, 0.3493]
    """
    a = _image(image)
    if depth_m is not None:
        if camera is None:
            raise ValueError("estimate_airlight needs the camera with depth_m: the horizon is found from the pixels' elevations")
        d = np.asarray(depth_m)
        if d.shape != a.shape[:2]:
            raise ValueError(f"depth_m has shape {d.shape}, the image is {a.shape[:2]}")
        # Every k-th row and column, at most ~2^16 pixels (k = 6 at 1920 x 1080): the horizon's
        # median does not need them all, and a dataset pays this once per photo.
        k = max(1, math.ceil(math.sqrt(d.size / 2**16)))
        sky = np.isinf(d[::k, ::k])
        if sky.any():
            ys, xs = np.nonzero(sky)
            ys, xs = ys * k, xs * k
            u, v = _slopes(camera.with_resolution(a.shape[1], a.shape[0]))
            us, vs = u[xs], v[ys]
            elevation = _rise(camera, us, vs) / np.sqrt(us**2 + vs**2 + 1.0)
            low = elevation <= np.quantile(elevation, HORIZON_FRACTION)
            px = np.median(a[ys[low], xs[low]], axis=0)
            return decode_srgb8(np.round(px).astype(np.uint8)) if a.dtype == np.uint8 else px.astype(np.float32)
    frac = float(top_fraction)
    if not 0.0 < frac <= 1.0:
        raise ValueError(f"top_fraction = {top_fraction} is outside the valid range (0, 1]")
    row, col = _core.atmospheric_light_pixel(a, integer("patch_px", patch_px, 1, 1001), frac)
    px = a[row, col]
    lin = decode_srgb8(px) if a.dtype == np.uint8 else px.astype(np.float32)
    hi, lo = float(lin.max()), float(lin.min())
    if hi > 0.0 and (hi - lo) / hi > NEUTRAL_GUARD:
        y = float(np.dot(lin.astype(np.float64), (0.2126, 0.7152, 0.0722)))
        return np.full(3, y, dtype=np.float32)
    return np.asarray(lin, dtype=np.float32)


def _rise(camera: Camera, u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """World y of the rays R (u, -v, -1) of slopes ``u``, ``v`` (broadcast), whose
    camera-space depth is 1."""
    r = np.asarray(camera.rotation, dtype=np.float64)
    rise: NDArray[np.float64] = r[1, 0] * u - r[1, 1] * v - r[1, 2]
    return rise


def _slopes(camera: Camera) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    fx, fy, cx, cy = camera.intrinsics()
    assert camera.width is not None and camera.height is not None  # intrinsics() checked
    u = (np.arange(camera.width, dtype=np.float64) + 0.5 - cx) / fx
    v = (np.arange(camera.height, dtype=np.float64) + 0.5 - cy) / fy
    return u, v


def ground_plane_depth(camera: Camera) -> NDArray[np.float32]:
    """Depth of a flat ground y = 0 seen by ``camera``, inf above the horizon: the depth a
    :class:`skyfall.PhotoScene` assumes when it is given none.

    The assumption: everything below the horizon is a level ground at the camera's height
    below it, and everything above is sky (far buildings and trees then fade like the sky, up
    to the cloud base). It is right for a road or a field and places walls too far; give a
    depth map (a sensor's, or an estimator's) where that matters.

    Parameters
    ----------
    camera : Camera
        With its resolution, above the ground (``position_m[1] > 0``).

    Returns
    -------
    ndarray of float32, shape (height, width)
        Depth along the optical axis, m.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera must be a skyfall.Camera, got {type(camera).__name__}")
    height_m = float(camera.position_m[1])
    if not height_m > 0.0:
        raise ValueError(f"the camera's position_m[1] = {height_m} must be > 0 m: the ground plane y = 0 lies below the camera")
    u, v = _slopes(camera)
    rise = _rise(camera, u[None, :], v[:, None])
    with np.errstate(divide="ignore"):
        depth = np.where(rise < 0.0, height_m / -rise, np.inf)
    return depth.astype(np.float32)


def level_camera(width: int, height: int, *, camera_height_m: float, horizon_row: float | None, vertical_fov_deg: float) -> Camera:
    """A camera ``camera_height_m`` above the ground, pitched so that its level horizon lies
    on ``horizon_row`` (pixel rows from the top; None: the image's middle, a level camera)."""
    h_m = in_range("camera_height_m", camera_height_m)
    cam = Camera((0.0, h_m, 0.0), vertical_fov_deg=vertical_fov_deg, width=width, height=height)
    if horizon_row is None:
        return cam
    row = in_range("horizon_row", horizon_row)
    _, fy, _, cy = cam.intrinsics()
    # A level ray has camera-space slope v = tan(pitch): it meets the image at cy + fy tan(pitch).
    pitch = math.degrees(math.atan((row - cy) / fy))
    if not -89.0 <= pitch <= 89.0:
        raise ValueError(f"horizon_row = {row} puts the camera's pitch at {pitch:.2f} deg, outside [-89, 89]")
    return Camera((0.0, h_m, 0.0), pitch_deg=pitch, vertical_fov_deg=vertical_fov_deg, width=width, height=height)


def assumed_depth(camera: Camera, *, sky_mask: Any, distance_m: float, ground_plane: bool) -> NDArray[np.float32]:
    """The depth a :class:`skyfall.PhotoScene` assumes for a photo without a depth map.

    ``inf`` on the sky mask (with ``ground_plane``, above the horizon only); elsewhere
    ``distance_m``, or with ``ground_plane`` the level ground's depth (:func:`ground_plane_depth`) up to ``distance_m``: the ground below the
    horizon, everything upright (and whatever the ground plane would put beyond
    ``distance_m``) at ``distance_m``.

    Parameters
    ----------
    camera : Camera
        With its resolution (and, for the ground plane, above the ground).
    sky_mask : array_like of bool, shape (height, width)
        True where the photo shows sky.
    distance_m : float
        m, in (0, 1e5].
    ground_plane : bool
        Whether the photo shows a level ground below its horizon.

    Returns
    -------
    ndarray of float32, shape (height, width)
    """
    dist = in_range("distance_m", distance_m)
    if camera.width is None or camera.height is None:
        raise ValueError("camera needs its resolution (Camera.with_resolution)")
    sky = np.asarray(sky_mask, dtype=bool)
    if sky.shape != (camera.height, camera.width):
        raise ValueError(f"sky_mask has shape {sky.shape}, the camera's frame is {(camera.height, camera.width)}")
    if ground_plane:
        ground = ground_plane_depth(camera)
        sky = sky & np.isinf(ground)  # the ground plane has no sky below its horizon
        d = np.minimum(ground, np.float32(dist))
    else:
        d = np.full(sky.shape, dist, np.float32)
    return np.where(sky, np.float32(np.inf), d).astype(np.float32)


def fill_depth_holes(depth_m: Any, sky_mask: Any) -> NDArray[np.float32]:
    """A depth map's ``NaN`` holes filled: sky (``inf``) where ``sky_mask`` is True, else the
    depth of the nearest pixel with data (Euclidean distance in px; ties by scipy's
    ``distance_transform_edt``, deterministic).

    Nearest-neighbour filling keeps the depths the map has (no blending across an object's
    edge) and fills a sparse LiDAR map (KITTI's) cell by cell.

    Raises
    ------
    ValueError
        When the map holds no pixel with data outside the sky.
    """
    from scipy import ndimage as ndi  # type: ignore[import-untyped]

    d = np.array(depth_m, dtype=np.float32)
    sky = np.asarray(sky_mask, dtype=bool) & np.isnan(d)
    d[sky] = np.inf
    holes = np.isnan(d)
    if not holes.any():
        return d
    known = ~holes & np.isfinite(d)
    if not known.any():
        raise ValueError("depth_m holds no finite depth outside the sky: nothing to fill its NaN holes from")
    _, (iy, ix) = ndi.distance_transform_edt(~known, return_indices=True)
    d[holes] = d[iy[holes], ix[holes]]
    return d


_FRAME_35MM_DIAGONAL_MM = math.hypot(36.0, 24.0)


def exif_vertical_fov_deg(metadata: Any, width: int, height: int) -> float | None:
    """The vertical field of view, degrees, that a photo's EXIF 35 mm-equivalent focal length
    implies (``Exif:FocalLengthIn35mmFilm``), or None without one.

    The 35 mm equivalent keeps the diagonal field of view of a 36 x 24 mm frame (CIPA DC-008):
    the diagonal angle is 2 atan(43.27 / (2 f35)), and the photo's own aspect ratio splits it.

    Parameters
    ----------
    metadata : mapping
        The file's attributes, e.g. from :func:`skyfall.io.read_image_with_metadata`.
    width, height : int
        The photo's size, px.

    Examples
    --------
    >>> round(exif_vertical_fov_deg({"Exif:FocalLengthIn35mmFilm": 26}, 4032, 3024), 2)
    53.06
    """
    f35 = metadata.get("Exif:FocalLengthIn35mmFilm") if hasattr(metadata, "get") else None
    try:
        f = float(f35) if f35 is not None else 0.0
    except (TypeError, ValueError):
        return None
    if not (math.isfinite(f) and f > 0.0) or width <= 0 or height <= 0:
        return None
    half_diag = math.atan(_FRAME_35MM_DIAGONAL_MM / (2.0 * f))
    return math.degrees(2.0 * math.atan(math.tan(half_diag) * height / math.hypot(width, height)))


def sky_level_camera(width: int, height: int, sky_mask: Any, *, vertical_fov_deg: float) -> Camera:
    """The camera a photo without depth or camera is taken with: at the origin, level (its
    horizon on the middle row) unless the sky mask reaches below the middle, then pitched up
    so that the horizon lies just under the lowest sky pixel (sky is never below the
    horizon, where its path through the rain would be endless).

    Parameters
    ----------
    width, height : int
        The photo's size, px.
    sky_mask : array_like of bool, shape (height, width)
        Where the photo shows sky.
    vertical_fov_deg : float
        Vertical field of view, degrees.

    Returns
    -------
    Camera
    """
    sky = np.asarray(sky_mask, dtype=bool)
    rows = np.flatnonzero(sky.any(axis=1))
    cam = Camera((0.0, 0.0, 0.0), vertical_fov_deg=vertical_fov_deg, width=width, height=height)
    if rows.size == 0 or rows[-1] + 1.0 <= height / 2.0:
        return cam
    _, fy, _, cy = cam.intrinsics()
    pitch = min(89.0, math.degrees(math.atan((rows[-1] + 1.0 - cy) / fy)))
    return Camera((0.0, 0.0, 0.0), pitch_deg=pitch, vertical_fov_deg=vertical_fov_deg, width=width, height=height)
