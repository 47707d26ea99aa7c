"""Shared helpers: reference tables live in tests/data with their source lines."""

from __future__ import annotations

import faulthandler
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

DATA = Path(__file__).parent / "data"

# A crash (a signal such as SIGABRT, not a failed test) leaves only the end of Python's fault
# dump in a log that keeps its last lines: where SKYFALL_CRASH_LOG names a file (``make test``
# sets it), the dump goes there and the running test's id to its ``.test`` twin, and the
# Makefile prints both, the crashing thread's frames first, after pytest dies.
_CRASH: dict[str, Any] = {}


def pytest_configure(config: pytest.Config) -> None:
    path = os.environ.get("SKYFALL_CRASH_LOG")
    if path and "dump" not in _CRASH:
        _CRASH["dump"] = open(path, "w")  # noqa: SIM115 (open for the whole session)
        _CRASH["test"] = Path(path + ".test")
        faulthandler.enable(file=_CRASH["dump"], all_threads=True)


def pytest_runtest_logstart(nodeid: str, location: tuple[str, int | None, str]) -> None:
    if "test" in _CRASH:
        _CRASH["test"].write_text(nodeid + "\n")


def pytest_unconfigure(config: pytest.Config) -> None:
    if "dump" in _CRASH:
        faulthandler.disable()
        _CRASH.pop("dump").close()


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
