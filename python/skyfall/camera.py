"""A camera: pose in a right-handed, +Y-up world (metres), intrinsics in pixels, and optionally
a thin lens (focal length, f-number, focus distance) whose blur circles soften near streaks.

The camera looks along its -Z axis with +X right and +Y up. Pixel (x, y) has its origin at
the top-left corner of the image and its centre at (x + 0.5, y + 0.5). Depth is metres along
the optical axis (not along the ray).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skyfall._validate import finite_vec3, float_array, in_range, inside, integer_in_range, refuse, world_position

__all__ = ["Camera"]


def _rotation_from_yaw_pitch(yaw_deg: float, pitch_deg: float) -> NDArray[np.float64]:
    y, p = math.radians(yaw_deg), math.radians(pitch_deg)
    # R_y(yaw) · R_x(pitch) written out (a 3x3 matmul would go through BLAS, whose worker
    # threads then spin on the cores the renderer uses).
    cy, sy, cp, sp = math.cos(y), math.sin(y), math.cos(p), math.sin(p)
    return np.array([[cy, sy * sp, sy * cp], [0.0, cp, -sp], [-sy, cy * sp, cy * cp]])


class Camera:
    """A pinhole camera, or a thin lens when ``f_number`` is given.

    Parameters
    ----------
    position_m : sequence of 3 float
        Camera centre in the world, m, each coordinate in [-1e7, 1e7]. Default (0, 1.6, 0): eye
        height.
    yaw_deg : float
        Heading about +Y, degrees, any finite angle; 0 looks along -Z, positive turns left
        (towards -X).
    pitch_deg : float
        Elevation of the view direction, degrees in [-89, 89]; positive looks up.
    look_at_m : sequence of 3 float, optional
        A world point to look at; overrides yaw and pitch (the horizon stays level).
    vertical_fov_deg : float, optional
        Vertical field of view, degrees in [0.001, 179), used when neither ``fy`` nor
        ``focal_length_mm`` is given. Default 60.
    width, height : int, optional
        Resolution, px, in [1, 16384]. Left out, the renderer's resolution is used.
    fx, fy, cx, cy : float, optional
        Intrinsics in px (need ``width`` and ``height``): ``fx``, ``fy`` in (0, 1e9],
        ``cx``, ``cy`` in [-1e9, 1e9]. Defaults: square pixels from the field of view,
        principal point at the image centre.
    exposure_s : float
        Shutter time, s, in [1e-6, 0.1]: streak length of moving drops (rain frames).
    velocity_m_s : sequence of 3 float
        The camera's own velocity, m/s, its speed in [0, 1000]: streaks follow the drops' motion
        relative to the camera, e.g. a car driving into the rain.
    focal_length_mm : float, optional
        Focal length f, mm, in [1, 5000]: sets the field of view with ``sensor_width_mm``
        (fx = fy = f / sensor width · frame width, px), in place of ``vertical_fov_deg`` or
        ``fx``/``fy`` (giving both is refused). Left out, the focal length in mm follows from
        the field of view (f = fx · sensor width / frame width).
    sensor_width_mm : float
        Sensor width, mm, in [1, 500]; default 36 (full frame). Maps the focal length and the
        blur circles between mm and px.
    f_number : float, optional
        f-number N, in [0.5, 256]: the lens's aperture is A = f / N. Left out: a pinhole,
        everything in focus (the frames are bit for bit those without a lens). Given, each
        streak is defocused by its blur circle (see ``focus_distance_m``).
    focus_distance_m : float, optional
        Distance in focus s, m along the optical axis, in (0, inf], beyond the focal length;
        needs ``f_number``; default inf (focused at infinity). A drop at depth z is blurred
        by the thin lens's circle of confusion c = A·f·|z − s| / (z·(s − f)) on the sensor
        (capped on screen at 1/16 of the frame's larger side), keeping its opacity.
    """

    def __init__(
        self,
        position_m: Sequence[float] = (0.0, 1.6, 0.0),
        *,
        yaw_deg: float = 0.0,
        pitch_deg: float = 0.0,
        look_at_m: Sequence[float] | None = None,
        vertical_fov_deg: float | None = None,
        width: int | None = None,
        height: int | None = None,
        fx: float | None = None,
        fy: float | None = None,
        cx: float | None = None,
        cy: float | None = None,
        exposure_s: float = 1.0 / 30.0,
        velocity_m_s: Sequence[float] = (0.0, 0.0, 0.0),
        focal_length_mm: float | None = None,
        sensor_width_mm: float = 36.0,
        f_number: float | None = None,
        focus_distance_m: float | None = None,
    ) -> None:
        self.position_m = world_position(position_m)
        self.velocity_m_s = finite_vec3("velocity_m_s", velocity_m_s)
        speed = float(np.linalg.norm(self.velocity_m_s))
        if not inside("velocity_m_s", speed):
            refuse("velocity_m_s", speed)  # the speed |v| is what has a range
        self.sensor_width_mm = in_range("sensor_width_mm", sensor_width_mm)
        self.focal_length_mm = None if focal_length_mm is None else in_range("focal_length_mm", focal_length_mm)
        if self.focal_length_mm is not None and (vertical_fov_deg is not None or fx is not None or fy is not None):
            raise ValueError("focal_length_mm sets the field of view: give it or vertical_fov_deg / fx / fy, not both")
        # None when the focal length sets the view (its vertical field then depends on the aspect).
        self.vertical_fov_deg: float | None = (
            None if self.focal_length_mm is not None else in_range("vertical_fov_deg", 60.0 if vertical_fov_deg is None else vertical_fov_deg)
        )
        self.f_number = None if f_number is None else in_range("f_number", f_number)
        if focus_distance_m is not None and self.f_number is None:
            raise ValueError("focus_distance_m needs f_number (a pinhole is in focus at every distance)")
        self.focus_distance_m: float | None = None
        if self.f_number is not None:
            s = math.inf if focus_distance_m is None else in_range("focus_distance_m", focus_distance_m)
            if self.focal_length_mm is not None and s <= self.focal_length_mm * 1e-3:
                raise ValueError(
                    f"focus_distance_m = {s} is not beyond the focal length {self.focal_length_mm * 1e-3:g} m"
                )
            self.focus_distance_m = s
        self.exposure_s = in_range("exposure_s", exposure_s)
        if look_at_m is not None:
            target = finite_vec3("look_at_m", look_at_m)
            d = target - self.position_m
            norm = float(np.linalg.norm(d))
            if norm == 0.0:
                raise ValueError("look_at_m must differ from position_m")
            d /= norm
            pitch = math.degrees(math.asin(max(-1.0, min(1.0, float(d[1])))))
            yaw = math.degrees(math.atan2(-float(d[0]), -float(d[2])))
            yaw_deg, pitch_deg = yaw, pitch
            if not -89.0 <= pitch <= 89.0:  # pitch_deg's range, [-89, 89] deg
                raise ValueError(
                    f"look_at_m = {target.tolist()} is {pitch:.1f} deg from level: within [-89, 89] deg (pitch_deg's range) only"
                )
        yaw_v, pitch_v = in_range("yaw_deg", yaw_deg), in_range("pitch_deg", pitch_deg)
        self.yaw_deg, self.pitch_deg = yaw_v, pitch_v
        self.rotation = _rotation_from_yaw_pitch(yaw_v, pitch_v)
        self.width = None if width is None else integer_in_range("width", width)
        self.height = None if height is None else integer_in_range("height", height)
        given = {k: v for k, v in {"fx": fx, "fy": fy, "cx": cx, "cy": cy}.items() if v is not None}
        if given and (self.width is None or self.height is None):
            raise ValueError(f"intrinsics {sorted(given)} need width and height")
        for k, v in given.items():
            in_range(k, v)
        self._fx, self._fy, self._cx, self._cy = fx, fy, cx, cy

    def with_resolution(self, width: int, height: int) -> Camera:
        """This camera at ``width`` x ``height`` (the field of view and the lens are kept)."""
        if self.width == width and self.height == height:
            return self
        if self._fx is not None or self._fy is not None:
            raise ValueError(
                f"camera intrinsics were given for {self.width}x{self.height}, the frame is {width}x{height}"
            )
        return self.replaced(width=width, height=height)

    def replaced(self, **changes: Any) -> Camera:
        """This camera with the constructor's keywords in ``changes`` set anew (its position,
        orientation, field of view, resolution, exposure, motion and lens otherwise kept; given
        intrinsics are not carried over).

        Examples
        --------
        >>> Camera((0.0, 1.6, 0.0), exposure_s=1 / 60).replaced(exposure_s=1 / 250).exposure_s
        0.004
        """
        kw: dict[str, Any] = {
            "yaw_deg": self.yaw_deg,
            "pitch_deg": self.pitch_deg,
            "vertical_fov_deg": self.vertical_fov_deg,
            "width": self.width,
            "height": self.height,
            "exposure_s": self.exposure_s,
            "velocity_m_s": tuple(self.velocity_m_s),
            "focal_length_mm": self.focal_length_mm,
            "sensor_width_mm": self.sensor_width_mm,
            "f_number": self.f_number,
            "focus_distance_m": self.focus_distance_m,
        }
        kw.update(changes)
        return Camera(tuple(self.position_m), **kw)

    def intrinsics(self) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) in px; needs the resolution."""
        if self.width is None or self.height is None:
            raise ValueError("the camera has no resolution yet: give width/height or use with_resolution()")
        if self.focal_length_mm is not None:
            fy = self.focal_length_mm / self.sensor_width_mm * self.width
        elif self._fy is not None:
            fy = self._fy
        else:
            fov = 60.0 if self.vertical_fov_deg is None else self.vertical_fov_deg
            fy = 0.5 * self.height / math.tan(math.radians(fov) / 2)
        fx = self._fx if self._fx is not None else fy
        cx = self._cx if self._cx is not None else 0.5 * self.width
        cy = self._cy if self._cy is not None else 0.5 * self.height
        return float(fx), float(fy), float(cx), float(cy)

    @property
    def world_from_camera(self) -> NDArray[np.float64]:
        """4 x 4 rigid transform from camera to world coordinates."""
        m = np.eye(4)
        m[:3, :3] = self.rotation
        m[:3, 3] = self.position_m
        return m

    def ray_directions(self) -> NDArray[np.float64]:
        """World-space directions of the rays through the pixel centres, as the renderer casts
        them: scaled so that their camera-space z is -1, so ``position_m + d * depth_m`` is a
        pixel's surface point for a frame's ``depth_m`` (normalise them for unit directions).
        Needs the resolution.

        Returns
        -------
        ndarray of float64, shape (height, width, 3)
        """
        fx, fy, cx, cy = self.intrinsics()  # refuses a camera without its resolution
        width, height = self.width or 0, self.height or 0
        u = (np.arange(width) + 0.5 - cx) / fx
        v = (np.arange(height) + 0.5 - cy) / fy
        uu, vv = np.meshgrid(u, v)
        d_cam = np.stack([uu, -vv, -np.ones_like(uu)], axis=-1)
        return np.asarray(d_cam @ np.asarray(self.rotation).T, dtype=np.float64)

    def project(self, points_m: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Project world points to pixels.

        Parameters
        ----------
        points_m : array_like, shape (N, 3)
            World points, m.

        Returns
        -------
        pixels : ndarray, shape (N, 2)
            Continuous (x, y) pixel coordinates; pixel (i, j)'s centre is (i + 0.5, j + 0.5).
        depth_m : ndarray, shape (N,)
            Depth along the optical axis, m (negative behind the camera).
        """
        p = float_array("points_m", points_m).reshape(-1, 3)
        fx, fy, cx, cy = self.intrinsics()
        pc = (p - self.position_m) @ self.rotation  # camera coordinates (R^T (p - c))
        depth = -pc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = cx + fx * pc[:, 0] / depth
            y = cy - fy * pc[:, 1] / depth
        return np.stack([x, y], axis=1), depth

    def __repr__(self) -> str:
        pos = ", ".join(f"{v:g}" for v in self.position_m)
        res = f", {self.width}x{self.height}" if self.width else ""
        view = (
            f"focal_length_mm={self.focal_length_mm:g}, sensor_width_mm={self.sensor_width_mm:g}"
            if self.focal_length_mm is not None
            else f"vertical_fov_deg={self.vertical_fov_deg:g}"
        )
        lens = "" if self.f_number is None else f", f_number={self.f_number:g}, focus_distance_m={self.focus_distance_m:g}"
        return f"Camera(position_m=({pos}), yaw_deg={self.yaw_deg:g}, pitch_deg={self.pitch_deg:g}, {view}{lens}{res})"
