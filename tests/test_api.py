"""The public names: every module's ``__all__`` lists names that exist (a name removed from a
module but left in its ``__all__`` breaks ``from skyfall.x import *``)."""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import skyfall

# The public modules, subpackages' included (skyfall.dataset.run); private ones (a name with a
# leading underscore anywhere in its path) are left out.
MODULES = [
    "skyfall",
    *(
        m.name
        for m in pkgutil.walk_packages(skyfall.__path__, prefix="skyfall.")
        if not any(part.startswith("_") for part in m.name.split("."))
    ),
]


@pytest.mark.parametrize("name", MODULES)
def test_every_exported_name_exists(name: str) -> None:
    mod = importlib.import_module(name)
    missing = [n for n in getattr(mod, "__all__", []) if not hasattr(mod, n)]
    assert not missing, f"{name}.__all__ lists {missing}"


def test_the_demos_and_references_are_outside_the_public_namespace() -> None:
    # The demo (its scenes, photos and plots) and the bundled references are private modules:
    # no public module is named for them, and `make demo` / `skyfall demo` reach the demo as
    # skyfall._demo.
    assert not [m for m in MODULES if "demo" in m or "reference" in m]
    for name in ("demo", "demo_photo", "demo_snow", "reference"):
        with pytest.raises(ImportError):
            importlib.import_module(f"skyfall.{name}")
    demo = importlib.import_module("skyfall._demo")
    assert callable(demo.main) and demo.DEMO_FRAMES


def test_python_m_skyfall_demo_and_the_command_reach_the_demo() -> None:
    import subprocess
    import sys

    from skyfall import cli

    done = subprocess.run([sys.executable, "-m", "skyfall._demo", "--help"], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "--out" in done.stdout
    with pytest.raises(SystemExit) as e:
        cli.main(["demo", "--help"])
    assert e.value.code == 0


def test_architecture_md_names_every_python_module() -> None:
    # ARCHITECTURE.md maps the code as built: every module of the package is named there by its
    # path under python/skyfall (a package by its folder, `dataset/`).
    from pathlib import Path

    root = Path(skyfall.__file__).resolve().parent
    text = (Path(__file__).resolve().parents[1] / "ARCHITECTURE.md").read_text()
    paths = sorted(p.relative_to(root).as_posix() for p in root.rglob("*.py") if "__pycache__" not in p.parts)
    assert "render.py" in paths and "dataset/run.py" in paths
    names = [p.removesuffix("__init__.py") if p.endswith("/__init__.py") else p for p in paths]
    missing = [n for n in names if f"`{n}`" not in text]
    assert not missing, f"ARCHITECTURE.md does not name {missing}"
