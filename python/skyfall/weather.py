"""The weather a frame is rendered in: one object that later effects extend."""

from __future__ import annotations

import math
from dataclasses import dataclass

from skyfall import _core, physics
from skyfall._validate import real

__all__ = ["Weather"]

KOSCHMIEDER = 3.912
"""-ln(0.02): visibility is where contrast falls to 2 %."""


@dataclass(frozen=True)
class Weather:
    """Weather parameters, validated on construction.

    Parameters
    ----------
    rain_rate_mm_h : float
        Rain rate, mm/h, in [0, 500].
    visibility_m : float
        Meteorological visibility of the air without rain, m, > 0 (``inf``: perfectly clear).
        Enters as Koschmieder extinction 3.912 / visibility_m.
    sky_illuminance_lux : float
        Horizontal illuminance from the overcast sky, lux, in (0, 150000]. Frames are in units
        of E/pi (a white surface under the open sky is 1.0); ``Frame.luminance_scale_cd_m2``
        converts to cd/m^2.
    """

    rain_rate_mm_h: float = 0.0
    visibility_m: float = math.inf
    sky_illuminance_lux: float = 10000.0

    def __post_init__(self) -> None:
        r = real("rain_rate_mm_h", self.rain_rate_mm_h)
        if not 0.0 <= r <= _core.MAX_RAIN_RATE_MM_H:
            raise ValueError(f"rain_rate_mm_h = {r} is outside the valid range [0, 500] mm/h")
        v = real("visibility_m", self.visibility_m)
        if not v > 0.0:
            raise ValueError(f"visibility_m = {v} is outside the valid range (0, inf] m")
        e = real("sky_illuminance_lux", self.sky_illuminance_lux)
        if not 0.0 < e <= 150000.0:
            raise ValueError(f"sky_illuminance_lux = {e} is outside the valid range (0, 150000] lx")
        object.__setattr__(self, "rain_rate_mm_h", r)
        object.__setattr__(self, "visibility_m", v)
        object.__setattr__(self, "sky_illuminance_lux", e)

    @property
    def air_extinction_per_m(self) -> float:
        """Koschmieder extinction of the air, 3.912 / visibility_m, 1/m."""
        return 0.0 if math.isinf(self.visibility_m) else KOSCHMIEDER / self.visibility_m

    @property
    def rain_extinction_per_m(self) -> float:
        """Extinction by rain, 1/m (:func:`skyfall.physics.rain_extinction_per_m`)."""
        return float(physics.rain_extinction_per_m(self.rain_rate_mm_h))

    @property
    def extinction_per_m(self) -> float:
        """Total extinction sigma = sigma_air + sigma_rain, 1/m."""
        return self.air_extinction_per_m + self.rain_extinction_per_m

    @property
    def luminance_scale_cd_m2(self) -> float:
        """E/pi, cd/m^2: multiply a frame's relative values by this to get luminance."""
        return self.sky_illuminance_lux / math.pi
