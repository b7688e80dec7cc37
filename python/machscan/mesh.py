"""Surface meshes (SPEC S1–S3; paper 002 §3): the triangulated theoretical and scanned surfaces
that mirror-milling compensation works on. :func:`delaunay_xy` meshes a height-field surface by
the Delaunay triangulation of its xy projection."""

from __future__ import annotations

from machscan._core import delaunay_xy

__all__ = ["delaunay_xy"]
