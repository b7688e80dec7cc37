"""ICP against Open3D and small_gicp, side by side in one run (issue #9 §6).

100,000 source points and 100,000 target points: two independent samplings of the same smooth
free-form patch (60 × 40 mm, asymmetric), 2 µm noise on the source, the source misplaced by
0.5 mm and 0.5°. Exactly 30 iterations (both stop thresholds 0), max correspondence distance
2 mm, point to point and point to plane (the target normals given to all). Best of --repeats
runs. Target: >= 2x Open3D for both methods.

small_gicp's ``align`` is timed with its kd-tree built inside the timed call, as machscan and
Open3D build theirs; its convergence epsilons are set to 0 so that it runs 30 iterations.

    python benchmarks/bench_registration.py [--points 100000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import open3d

import machscan

reg = open3d.pipelines.registration


def patch(n, rng):
    x, y = rng.uniform(-30, 30, n), rng.uniform(-20, 20, n)
    g = np.exp(-((x - 6) ** 2) / 60 - (y + 3) ** 2 / 90)
    z = 4 * g + 0.015 * x * y + 0.04 * x
    fx = 4 * g * (-2 * (x - 6) / 60) + 0.015 * y + 0.04
    fy = 4 * g * (-2 * (y + 3) / 90) + 0.015 * x
    n = np.column_stack([-fx, -fy, np.ones(n)])
    return np.column_stack([x, y, z]), n / np.linalg.norm(n, axis=1, keepdims=True)


def rigid(deg, t):
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    m = np.eye(4)
    m[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    m[:3, 3] = t
    return m


def best(fn, repeats):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    target, normals = patch(args.points, rng)
    sample, _ = patch(args.points, rng)
    sample += rng.normal(0, 0.002, sample.shape)
    misplace = rigid(0.5, (0.3, -0.3, 0.25))
    source = sample @ misplace[:3, :3].T + misplace[:3, 3]
    truth = np.linalg.inv(misplace)
    dist, iters = 2.0, 30

    tgt_o3d = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(target))
    tgt_o3d.normals = open3d.utility.Vector3dVector(normals)
    src_o3d = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(source))
    crit = reg.ICPConvergenceCriteria(relative_fitness=0, relative_rmse=0, max_iteration=iters)

    import small_gicp

    src_sg, tgt_sg = small_gicp.PointCloud(source), small_gicp.PointCloud(target)
    small_gicp.estimate_normals(tgt_sg, small_gicp.KdTree(tgt_sg), num_neighbors=20)

    print(f"ICP, {len(source):,} -> {len(target):,} points, {iters} iterations, {os.cpu_count()} cores")
    print(f"  {'method':<15} {'machscan':>10} {'Open3D':>10} {'small_gicp':>11} {'vs Open3D':>10}   pose error (max |ΔT|)")
    for method, o3_est, sg_type in [
        ("point_to_point", reg.TransformationEstimationPointToPoint(), "ICP"),
        ("point_to_plane", reg.TransformationEstimationPointToPlane(), "PLANE_ICP"),
    ]:
        t_ms, r = best(lambda method=method: machscan.icp(
            source, target, dist, method=method, target_normals=normals, max_iterations=iters,
            relative_fitness=0, relative_rmse=0), args.repeats)
        t_o3, o3 = best(lambda est=o3_est: reg.registration_icp(src_o3d, tgt_o3d, dist, np.eye(4), est, crit),
                        args.repeats)

        def run_sg(sg_type=sg_type):
            tree = small_gicp.KdTree(tgt_sg, num_threads=2)
            return small_gicp.align(tgt_sg, src_sg, tree, registration_type=sg_type, max_correspondence_distance=dist,
                                    num_threads=2, max_iterations=iters, rotation_epsilon=0.0, translation_epsilon=0.0)

        t_sg, sg = best(run_sg, args.repeats)
        err = [np.abs(t - truth).max() for t in (r.transformation, o3.transformation, sg.T_target_source)]
        print(f"  {method:<15} {t_ms * 1e3:8.0f} ms {t_o3 * 1e3:8.0f} ms {t_sg * 1e3:9.0f} ms {t_o3 / t_ms:9.1f}x   "
              f"{err[0]:.1e} / {err[1]:.1e} / {err[2]:.1e};  machscan vs Open3D "
              f"{np.abs(r.transformation - o3.transformation).max():.1e}")


if __name__ == "__main__":
    main()
