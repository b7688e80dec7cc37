"""Fixtures shared by the test modules: the data folder and the synthetic scans, built once per
session (a full groove scan takes seconds)."""

import sys
from pathlib import Path

import pytest

# The NumPy reference implementations live beside the tests.
sys.path.insert(0, str(Path(__file__).parent))

from machscan import synth
from paths import DATA


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """`data/`: the PCL bunny scans, the exact geodesic meshes, the Stanford bunny."""
    assert DATA.is_dir(), f"the data folder is missing: {DATA}"
    return DATA


@pytest.fixture(scope="session")
def groove_scan():
    """`synth.groove_scan(seed=0)`, the demo's scan, and its truth."""
    return synth.groove_scan(seed=0)


@pytest.fixture(scope="session")
def groove_report(groove_scan):
    """The groove inspection of the demo's scan with the default settings."""
    from machscan.inspection import inspect_grooves

    scan, truth = groove_scan
    return inspect_grooves(scan, truth.nominal_polylines)


@pytest.fixture(scope="session")
def small_groove_scan():
    """A cropped, decimated groove scan (800 readings, every 100th frame): seconds less."""
    return synth.groove_scan(seed=0, readings=800, keep_every=100)
