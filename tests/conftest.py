"""Shared helpers: reference tables live in tests/data with their source lines."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

DATA = Path(__file__).parent / "data"


def load_csv(name: str) -> dict[str, np.ndarray]:
    """Read a CSV from tests/data whose leading '#' lines name its source."""
    lines = [ln for ln in (DATA / name).read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    header = lines[0].split(",")
    rows = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    return {h: rows[:, i] for i, h in enumerate(header)}


@pytest.fixture(scope="session")
def gunn_kinzer() -> tuple[np.ndarray, np.ndarray]:
    t = load_csv("gunn_kinzer_1949_fall_speed.csv")
    return t["diameter_mm"], t["fall_speed_m_s"]
