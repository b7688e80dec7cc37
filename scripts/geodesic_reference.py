"""Reference distances from pygeodesic (Kirsanov's exact MMP) for the Rust tests of the exact
geodesic kernel (`crates/core/src/mesh/geodesic_exact.rs`), which read them when present:

    python scripts/geodesic_reference.py [out_dir]      # default target/georef

Writes <out_dir>/<mesh>.txt for the flat and hedgehog meshes of data/geodesic-flat-mesh
and the Stanford bunny of data/stanford-bunny-mesh: "nv nf ns", nv vertex lines (repr
floats: exactly the float64 coordinates given to pygeodesic), nf face lines, then per source a line
"source s seconds" (pygeodesic's time for that source) and nv distances ("inf" where unreached).
The files are data, not committed.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pygeodesic.geodesic as geodesic
import trimesh

DATA = Path(__file__).resolve().parents[1] / "data"


def read_txt(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The "nv nf" / vertices / faces text format of Kirsanov's examples."""
    with open(path) as fh:
        nv, nf = map(int, fh.readline().split())
        rows = [line.split() for line in fh if line.strip()]
    return np.array(rows[:nv], dtype=np.float64), np.array(rows[nv : nv + nf], dtype=np.int32)


def write(out: Path, name: str, v: np.ndarray, f: np.ndarray, sources: list[int]) -> None:
    v = np.ascontiguousarray(v, dtype=np.float64)
    f = np.ascontiguousarray(f, dtype=np.int32)
    geo = geodesic.PyGeodesicAlgorithmExact(v, f)
    with open(out / f"{name}.txt", "w") as fh:
        fh.write(f"{len(v)} {len(f)} {len(sources)}\n")
        fh.writelines(" ".join(repr(float(c)) for c in p) + "\n" for p in v)
        fh.writelines(" ".join(str(int(i)) for i in t) + "\n" for t in f)
        for s in sources:
            start = time.perf_counter()
            d, _ = geo.geodesicDistances(np.array([s]), None)
            seconds = time.perf_counter() - start
            d = np.where(np.asarray(d) > 1e99, np.inf, d)  # pygeodesic's "unreached" is 1e100
            fh.write(f"source {s} {seconds!r}\n")
            fh.writelines(repr(float(x)) + "\n" for x in d)
            print(f"{name} source {s}: {seconds:.3f} s", flush=True)


def main() -> None:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "target/georef")
    out.mkdir(parents=True, exist_ok=True)
    write(out, "flat", *read_txt(DATA / "geodesic-flat-mesh/flat_triangular_mesh.txt"), [25, 0, 60, 120])
    write(out, "hedgehog", *read_txt(DATA / "geodesic-flat-mesh/hedgehog_mesh.txt"), [0, 17, 150, 299])
    bunny = trimesh.load(DATA / "stanford-bunny-mesh/stanford_bunny.ply", process=False)
    used = np.unique(np.asarray(bunny.faces).ravel())
    extra = [int(x) for x in np.random.default_rng(10).choice(used, 5, replace=False)]
    write(out, "bunny", np.asarray(bunny.vertices), np.asarray(bunny.faces), [0, 14558, 13039, *extra])


if __name__ == "__main__":
    main()
