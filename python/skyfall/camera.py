"""A pinhole camera: pose in a right-handed, +Y-up world (metres) and intrinsics in pixels.

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
    """A pinhole camera.

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
    vertical_fov_deg : float
        Vertical field of view, degrees in [0.001, 179), used when ``fy`` is not given.
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
    """

    def __init__(
        self,
        position_m: Sequence[float] = (0.0, 1.6, 0.0),
        *,
        yaw_deg: float = 0.0,
        pitch_deg: float = 0.0,
        look_at_m: Sequence[float] | None = None,
        vertical_fov_deg: float = 60.0,
        width: int | None = None,
        height: int | None = None,
        fx: float | None = None,
        fy: float | None = None,
        cx: float | None = None,
        cy: float | None = None,
        exposure_s: float = 1.0 / 30.0,
        velocity_m_s: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        self.position_m = world_position(position_m)
        self.velocity_m_s = finite_vec3("velocity_m_s", velocity_m_s)
        speed = float(np.linalg.norm(self.velocity_m_s))
        if not inside("velocity_m_s", speed):
            refuse("velocity_m_s", speed)  # the speed |v| is what has a range
        self.vertical_fov_deg = in_range("vertical_fov_deg", vertical_fov_deg)
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
        """This camera at ``width`` x ``height`` (the field of view is kept)."""
        if self.width == width and self.height == height:
            return self
        if self._fx is not None or self._fy is not None:
            raise ValueError(
                f"camera intrinsics were given for {self.width}x{self.height}, the frame is {width}x{height}"
            )
        return Camera(
            tuple(self.position_m),
            yaw_deg=self.yaw_deg,
            pitch_deg=self.pitch_deg,
            vertical_fov_deg=self.vertical_fov_deg,
            width=width,
            height=height,
            exposure_s=self.exposure_s,
            velocity_m_s=tuple(self.velocity_m_s),
        )

    def intrinsics(self) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) in px; needs the resolution."""
        if self.width is None or self.height is None:
            raise ValueError("the camera has no resolution yet: give width/height or use with_resolution()")
        fy = self._fy if self._fy is not None else 0.5 * self.height / math.tan(math.radians(self.vertical_fov_deg) / 2)
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
        return f"Camera(position_m=({pos}), yaw_deg={self.yaw_deg:g}, pitch_deg={self.pitch_deg:g}, vertical_fov_deg={self.vertical_fov_deg:g}{res})"
