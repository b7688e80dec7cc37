"""Synthetic scans and parts with exact ground truth, for tests, demos and benchmarks.

* :mod:`machscan.synth.grooves`: paper 000 groove plate scans (:func:`groove_scan`) with their truth;
  :mod:`machscan.synth.frames`: single groove frames (:func:`groove_frames`) and frames across several
  (:func:`multi_groove_frames`);
  :mod:`machscan.synth.pocket`: a pocketed plate for the octree simplification (:func:`pocket_plate`).
* :mod:`machscan.synth.blade`: paper 003 turbine blade (:class:`Blade`) and touch-probe simulator
  (:class:`TouchProbe`, :func:`misplacement`).
* :mod:`machscan.synth.grinding`: allowance clouds for grinding paths (:class:`WavyPanel`, :func:`blade_allowance`).
* :mod:`machscan.synth.skin`: paper 002 thin skin bent when clamped (:class:`BentSkin`), for mirror milling.

The package is pure NumPy (it does not use the compiled core), so its truth is independent of the code
it tests.
"""

from machscan.synth.blade import Blade, TouchProbe, misplacement
from machscan.synth.frames import GROOVE_SHAPES, GrooveFrames, MultiGrooveFrames, groove_frames, multi_groove_frames
from machscan.synth.grinding import AllowanceCloud, WavyPanel, blade_allowance
from machscan.synth.grooves import (
    DEFAULT_C2_OFFSET,
    DEFAULT_MOUNT,
    PLATE,
    ContourShape,
    Deflection,
    GrooveTruth,
    PeriodicProfile,
    SurfaceError,
    default_contours,
    flat_plate_scan,
    groove_scan,
    surface_error,
)
from machscan.synth.pocket import pocket_plate
from machscan.synth.skin import BentSkin
from machscan.synth.sphere import SPHERE_POSES, SphereTruth, sphere_scan

__all__ = [
    "DEFAULT_C2_OFFSET",
    "DEFAULT_MOUNT",
    "GROOVE_SHAPES",
    "PLATE",
    "SPHERE_POSES",
    "AllowanceCloud",
    "BentSkin",
    "Blade",
    "ContourShape",
    "Deflection",
    "GrooveFrames",
    "GrooveTruth",
    "MultiGrooveFrames",
    "PeriodicProfile",
    "SphereTruth",
    "SurfaceError",
    "TouchProbe",
    "WavyPanel",
    "blade_allowance",
    "default_contours",
    "flat_plate_scan",
    "groove_frames",
    "groove_scan",
    "misplacement",
    "multi_groove_frames",
    "pocket_plate",
    "sphere_scan",
    "surface_error",
]
