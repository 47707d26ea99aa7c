"""Published data bundled with skyfall (for plots and comparisons; tests keep their own copies)."""

from __future__ import annotations

from importlib import resources

import numpy as np
from numpy.typing import NDArray

__all__ = ["gunn_kinzer_1949"]


def gunn_kinzer_1949() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Measured raindrop fall speeds in still air (Gunn & Kinzer 1949, J. Meteor. 6, Table 2).

    Returns
    -------
    diameter_mm, fall_speed_m_s : ndarray
        35 drops, 0.078-5.8 mm, at about 1013 hPa, 20 degC, 50 % RH.
    """
    text = resources.files("skyfall").joinpath("data/gunn_kinzer_1949.csv").read_text()
    rows = [line.split(",") for line in text.splitlines() if line and not line.startswith("#")][1:]
    return np.array([float(r[0]) for r in rows]), np.array([float(r[1]) for r in rows])
