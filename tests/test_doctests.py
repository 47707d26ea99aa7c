"""Every docstring example in the package runs and prints what it shows.

Run from tests/ (not ``--doctest-modules`` in the Makefile) so that plain ``pytest tests``,
the command the README and the contributors use, runs them too, on the installed package
(the one the rest of the suite imports), one test per module so a failure names it.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import numpy as np
import pytest

import skyfall

NUMPY_PRINT_DEFAULTS = {
    "edgeitems": 3,
    "threshold": 1000,
    "floatmode": "maxprec",
    "precision": 8,
    "suppress": False,
    "linewidth": 75,
    "nanstr": "nan",
    "infstr": "inf",
    "sign": "-",
    "formatter": None,
    "legacy": False,
}

MODULES = sorted(
    m.name for m in pkgutil.walk_packages(skyfall.__path__, prefix="skyfall.") if not m.name.startswith("skyfall._core")
)
# Modules whose public functions carry examples: an example lost from any of them fails below.
WITH_EXAMPLES = {"skyfall.physics", "skyfall.io", "skyfall.rain", "skyfall._reference", "skyfall.render", "skyfall.scenes", "skyfall.testing"}


def _examples(name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder().find(module, name) if t.examples]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    # numpy's own print options, as a user has them: importing colour-science (other tests do)
    # switches numpy to its 1.13 legacy printing for the whole process
    with np.printoptions(**NUMPY_PRINT_DEFAULTS):
        failed = sum(runner.run(test, out=report.append).failed for test in _examples(name))
    assert failed == 0, "".join(report)


def test_the_documented_modules_have_examples():
    assert set(WITH_EXAMPLES) <= set(MODULES)
    for name in sorted(WITH_EXAMPLES):
        assert sum(len(t.examples) for t in _examples(name)) > 0, f"{name} lost its docstring examples"
