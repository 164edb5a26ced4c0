"""The documentation's examples run as written.

Every fenced ``python`` block of the pages in ``DOC_PAGES`` is executed in order, in one
namespace per page (so later blocks use what earlier ones defined), and the doctests embedded in
the packages' docstrings run too.
"""

from __future__ import annotations

import doctest
import importlib
import re
import sys
import types
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parents[1] / "docs"
DOC_PAGES = ["api.md", "extending.md", "closed_loop.md", "sequencer.md"]
DOCTEST_MODULES = ["robots"]

_BLOCK = re.compile(r"^```python\n(.*?)^```", re.MULTILINE | re.DOTALL)


def python_blocks(page: str) -> list[str]:
    """The fenced python blocks of docs/``page``, in order."""
    return _BLOCK.findall((DOCS / page).read_text())


@pytest.fixture
def isolated_registries(monkeypatch):
    """Robots and scenarios registered by an example are forgotten after the test."""
    import robots.registry
    import sim.scenarios.base

    monkeypatch.setattr(robots.registry, "_BUILDERS", dict(robots.registry._BUILDERS))
    monkeypatch.setattr(sim.scenarios.base, "_REGISTRY", dict(sim.scenarios.base._REGISTRY))


@pytest.mark.parametrize("page", DOC_PAGES)
def test_documented_examples_run(page, tmp_path, monkeypatch, isolated_registries):
    blocks = python_blocks(page)
    assert blocks, f"docs/{page} has no python example"
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    # A real module, so that dataclasses and pickling defined in the examples resolve their module.
    module = types.ModuleType(f"docs_{page.replace('.', '_')}")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    namespace = module.__dict__
    for index, block in enumerate(blocks):
        try:
            exec(compile(block, f"docs/{page}[block {index}]", "exec"), namespace)
        except Exception as err:  # pragma: no cover - the message is the point
            raise AssertionError(f"docs/{page}, python block {index} failed: {err!r}\n{block}") from err


@pytest.mark.parametrize("module_name", DOCTEST_MODULES)
def test_docstring_examples_run(module_name):
    module = importlib.import_module(module_name)
    result = doctest.testmod(module, verbose=False)
    assert result.attempted > 0, f"{module_name} has no doctest"
    assert result.failed == 0
