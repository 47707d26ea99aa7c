"""What the package imports is what pyproject.toml declares."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "python" / "skyfall"
# Imported, deliberately not declared: skyfall._reference.canyon_illuminance is a test and
# bench reference that says `pip install scipy` when scipy is missing.
UNDECLARED = {"scipy"}


def _name(requirement: str) -> str:
    return re.split(r"[<>=!~;\[ ]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def declared() -> tuple[set[str], set[str]]:
    """(required, optional) distribution names in pyproject.toml."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    required = {_name(r) for r in project["dependencies"]}
    optional = {_name(r) for reqs in project.get("optional-dependencies", {}).values() for r in reqs}
    return required, optional


def imported_modules(path: Path) -> set[str]:
    """Top-level names of the third-party modules a file imports (anywhere in it)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return {n for n in names if n not in sys.stdlib_module_names and n != "skyfall"}


def test_every_import_is_a_declared_dependency():
    required, optional = declared()
    dists = packages_distributions()
    missing = []
    for path in sorted(PACKAGE.rglob("*.py")):  # subpackages (dataset/, _demo/) included
        for module in sorted(imported_modules(path) - UNDECLARED):
            names = {_name(d) for d in dists.get(module, [module])}
            if not names & (required | optional):
                missing.append(f"{path.relative_to(PACKAGE)} imports {module} ({', '.join(sorted(names))})")
    assert not missing, "undeclared in pyproject.toml: " + "; ".join(missing)


def test_render_sequence_needs_tqdm_and_it_is_required():
    # render.py imports it for Renderer.render_sequence: core API, so not an extra
    assert "tqdm" in imported_modules(PACKAGE / "render.py")
    required, _ = declared()
    assert {"numpy", "tqdm"} <= required
    _, optional = declared()
    assert "openimageio" in optional  # skyfall[io]
