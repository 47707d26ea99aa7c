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
