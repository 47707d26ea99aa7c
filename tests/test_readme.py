"""The README's Python blocks run as written: in order, in one namespace, in a temporary
folder (the files they write land there), as a new user would paste them."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def python_blocks() -> list[tuple[int, str]]:
    """(first line number, code) of every ```python block of the README."""
    text = README.read_text()
    return [(text.count("\n", 0, m.start(1)) + 1, m.group(1)) for m in BLOCK.finditer(text)]


def test_every_readme_block_runs_in_order(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    blocks = python_blocks()
    assert len(blocks) >= 5  # the tour, frames, rain, 8-bit, sky
    namespace: dict[str, object] = {"__name__": "__readme__"}
    for line, code in blocks:
        # padded with blank lines so a traceback points at the README's own line numbers
        exec(compile("\n" * (line - 1) + code, str(README), "exec"), namespace)
    # what the blocks say they write, and the photo the later blocks take from a frame
    for name in ("rain.exr", "streaks.png", "street.exr", "street.png", "rain_00.png", "rainy_0.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    image, depth = namespace["image_uint8"], namespace["depth_m"]
    assert isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.shape == (720, 1280, 3)
    assert isinstance(depth, np.ndarray) and depth.shape == (720, 1280) and np.isinf(depth).any()
    alpha = np.load(tmp_path / "rain_alpha_0.npy")
    assert alpha.shape == depth.shape and 0.0 < float(alpha.max()) <= 1.0
