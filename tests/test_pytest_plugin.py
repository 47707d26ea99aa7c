"""skyfall's pytest plugin for real: pytester runs users' test files in a new pytest process,
where the plugin comes in through the installed ``pytest11`` entry point, as it does for users
(a subprocess: in-process runs drop the modules they imported, and numpy's extensions cannot
be loaded twice)."""

from __future__ import annotations

import re
import tomllib
from importlib.metadata import entry_points
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[1]


def test_the_entry_point_is_declared_and_installed():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["entry-points"]["pytest11"] == {"skyfall": "skyfall.pytest_plugin"}
    installed = {e.name: e.value for e in entry_points(group="pytest11")}
    assert installed.get("skyfall") == "skyfall.pytest_plugin", "reinstall: make build"


USER_TESTS = '''
import numpy as np
import pytest
import skyfall
from skyfall import PhotoScene, Weather
from skyfall.testing import with_weather

SEEN = []


@pytest.fixture
def image():
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (18, 32, 3), dtype=np.uint8)


@pytest.mark.parametrize("rate", [0.0, 2.0, 20.0])
def test_sweep(rate, image, skyfall_renderer):
    renderer = skyfall_renderer(32, 18)
    SEEN.append((skyfall_renderer, renderer))
    rainy = with_weather(image, rain_rate_mm_h=rate, seed=5, renderer=renderer)
    direct = skyfall.Renderer(32, 18, backend="cpu").render_srgb8(PhotoScene(image), Weather(rain_rate_mm_h=rate), seed=5)
    assert rainy.tobytes() == direct.tobytes()
    assert (rate == 0.0) == (rainy.tobytes() == image.tobytes())


def test_one_fixture_and_one_renderer_per_size_for_the_session(skyfall_renderer):
    assert len(SEEN) == 3
    assert all(cache is skyfall_renderer and r is skyfall_renderer(32, 18) for cache, r in SEEN)
    assert skyfall_renderer(18, 32) is not skyfall_renderer(32, 18)
    assert isinstance(skyfall_renderer(32, 18), skyfall.Renderer)
'''


def test_a_users_rain_sweep_runs_under_pytest(pytester: pytest.Pytester):
    pytester.makepyfile(test_user=USER_TESTS)
    pytester.makepyfile(test_other="def test_same_session(skyfall_renderer):\n    import test_user\n    assert test_user.SEEN[0][0] is skyfall_renderer\n")
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "test_user.py", "test_other.py")
    result.assert_outcomes(passed=5)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--fixtures", "test_user.py")
    result.stdout.fnmatch_lines(["*skyfall_renderer*session*", "*Renderers by size*"])


def test_the_readme_example_runs_under_pytest(pytester: pytest.Pytester):
    text = (ROOT / "README.md").read_text()
    blocks = [b for b in re.findall(r"^```python\n(.*?)^```", text, re.S | re.M) if "def test_my_model_in_rain" in b]
    assert len(blocks) == 1
    pytester.makepyfile(test_my_model=blocks[0])
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-v")
    result.assert_outcomes(passed=6)
    result.stdout.fnmatch_lines(["*test_my_model_in_rain?0.0? PASSED*", "*test_my_model_in_rain?25.0? PASSED*", "*test_my_model_across_drawn_weather?2? PASSED*"])


def test_the_plugin_imports_nothing_of_skyfall():
    # a project that has skyfall installed but does not use it pays nothing at pytest start
    source = (ROOT / "python" / "skyfall" / "pytest_plugin.py").read_text()
    top = [ln for ln in source.splitlines() if ln.startswith(("import ", "from "))]
    assert all("skyfall" not in ln for ln in top), top
