"""Shared test fixtures."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

# CI runs the same (derandomised) hypothesis examples every time; locally they vary from run to run
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

REPO = Path(__file__).resolve().parents[1]
SHARED_TABLE1 = REPO.parent / "shared" / "reference" / "table1.csv"


@pytest.fixture(scope="session")
def ankarasat3():
    from satchain import load_preset

    return load_preset("ankarasat3")


@pytest.fixture(scope="session")
def table1_path():
    """The shared reference Table 1 when the checkout sits beside shared/, else None (packaged copy)."""
    return SHARED_TABLE1 if SHARED_TABLE1.exists() else None
