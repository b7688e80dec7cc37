"""Point cloud core against Open3D, side by side on the same data (issue #4 targets):

- read 1 M points: binary PLY ≥ 1.5×, ASCII PLY ≥ 3×, ASCII PCD ≥ 3×, binary PCD ≥ 2× faster
  than open3d.io.read_point_cloud;
- voxel grid on 1 M points, statistical and radius outlier removal on 200 k, normals (k = 20)
  on 200 k: each ≥ 2× faster;
- peak memory of the voxel grid on 10 M points below 2× the input array (run with --memory).

Also, without a target: the k-nearest graph of 200 k points against Open3D's tensor
NearestNeighborSearch and scipy's cKDTree; reading 1 M points of LAS and LAZ (point format 6,
intensity and one float64 extra dimension) against laspy (+ lazrs), every field, not only xyz.

    python benchmarks/bench_cloud.py [--memory]
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import open3d
from scipy.spatial import cKDTree
from timing import best_time

import machscan


def row(name, ms, ref, ref_name="open3d"):
    print(f"  {name:<34} machscan {ms * 1e3:8.1f} ms   {ref_name} {ref * 1e3:8.1f} ms   ratio {ref / ms:5.1f}x")


def scanned_surface(n, seed=0):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 500, n), rng.uniform(0, 300, n)
    return np.column_stack([x, y, 5 * np.sin(x / 40) * np.cos(y / 30) + rng.normal(0, 0.01, n)])


def files(d: Path, p: np.ndarray) -> dict[str, Path]:
    pc = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))
    out = {}
    for name, kw in (("binary PLY", dict(write_ascii=False)), ("ASCII PLY", dict(write_ascii=True))):
        path = d / (name.replace(" ", "_") + ".ply")
        open3d.io.write_point_cloud(str(path), pc, **kw)
        out[name] = path
    for name, kw in (("ASCII PCD", dict(write_ascii=True)), ("binary PCD", dict(write_ascii=False)),
                     ("binary_compressed PCD", dict(write_ascii=False, compressed=True))):
        path = d / (name.replace(" ", "_") + ".pcd")
        open3d.io.write_point_cloud(str(path), pc, **kw)
        out[name] = path
    return out


def memory_child(n: int) -> None:
    p = scanned_surface(n)
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    machscan.voxel_downsample(p, 0.5)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(f"  voxel grid on {n / 1e6:.0f} M points: input {p.nbytes / 2**20:.0f} MiB, process peak {peak / 2**20:.0f} MiB "
          f"(before the call {base / 2**20:.0f} MiB): added {(peak - base) / p.nbytes:.2f}x the input")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--memory", action="store_true", help="also measure the voxel grid's peak memory on 10 M points")
    ap.add_argument("--memory-child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child:
        memory_child(args.memory_child)
        return
    print(f"{os.cpu_count()} cores, open3d {open3d.__version__}")
    p1m = scanned_surface(1_000_000)
    with tempfile.TemporaryDirectory() as d:
        print("reading 1 M points:")
        for name, path in files(Path(d), p1m).items():
            ms = best_time(lambda path=path: machscan.read_points(path))
            o3 = best_time(lambda path=path: open3d.io.read_point_cloud(str(path)))
            assert np.allclose(machscan.read_points(path), np.asarray(open3d.io.read_point_cloud(str(path)).points))
            row(name, ms, o3)
        import laspy

        header = laspy.LasHeader(point_format=6, version="1.4")
        header.scales, header.offsets = [1e-4] * 3, [0.0, 0.0, -10.0]
        header.add_extra_dims([laspy.ExtraBytesParams("allowance", "f8")])
        las = laspy.LasData(header)
        las.x, las.y, las.z = p1m[:, 0], p1m[:, 1], p1m[:, 2]
        las.intensity = np.arange(len(p1m)) % 65536
        las.allowance = p1m[:, 2] * 0.01
        for suffix in (".las", ".laz"):
            path = Path(d) / f"cloud{suffix}"
            las.write(path)
            # LAZ against lazrs on two threads (laspy's default) and on one (machscan's).
            backends = [None] if suffix == ".las" else [laspy.LazBackend.LazrsParallel, laspy.LazBackend.Lazrs]
            for backend in backends:

                def by_laspy(path=path, backend=backend):
                    f = laspy.read(path, laz_backend=backend)
                    return np.column_stack([f.x, f.y, f.z]), {n: np.asarray(f[n]) for n in f.point_format.dimension_names}

                c, (ref, _) = machscan.io.read(path), by_laspy()
                assert np.array_equal(c.points, ref)
                label = suffix[1:].upper() + ("" if backend is None else f", {backend.name}")
                row(f"{label} (every field)", best_time(lambda path=path: machscan.io.read(path)),
                    best_time(by_laspy), "laspy")
    pc1m = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p1m))
    print("filters:")
    row("voxel grid, 1 M points", best_time(lambda: machscan.voxel_downsample(p1m, 1.0)),
        best_time(lambda: pc1m.voxel_down_sample(1.0)))
    p200 = scanned_surface(200_000, seed=1)
    pc200 = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p200))
    row("statistical outliers, 200 k, k=20", best_time(lambda: machscan.remove_statistical_outliers(p200, 20, 2.0)),
        best_time(lambda: pc200.remove_statistical_outlier(20, 2.0)))
    row("radius outliers, 200 k, r=2", best_time(lambda: machscan.remove_radius_outliers(p200, 2.0, 5)),
        best_time(lambda: pc200.remove_radius_outlier(5, 2.0)))

    def o3_normals():
        c = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p200))
        c.estimate_normals(open3d.geometry.KDTreeSearchParamKNN(20))

    row("normals k=20, 200 k", best_time(lambda: machscan.estimate_normals(p200, k=20)), best_time(o3_normals))

    def o3_knn():
        nns = open3d.core.nns.NearestNeighborSearch(open3d.core.Tensor(p200))
        nns.knn_index()
        return nns.knn_search(open3d.core.Tensor(p200), 20)

    print("neighbor search (tree built in the call):")
    row("k-nearest graph k=20, 200 k", best_time(lambda: machscan.knn_graph(p200, 20)), best_time(o3_knn))
    row("k-nearest graph k=20, 200 k", best_time(lambda: machscan.knn_graph(p200, 20)),
        best_time(lambda: cKDTree(p200).query(p200, 20, workers=-1)), "scipy cKDTree (2 workers)")
    if args.memory:
        subprocess.run([sys.executable, __file__, "--memory-child", "10000000"], check=True)


if __name__ == "__main__":
    main()
