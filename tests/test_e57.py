"""E57 files against pye57 (libE57Format) on the same files, each library reading what the
other writes (issue #34 §1). E57 stores metres, machscan mm."""

from __future__ import annotations

import numpy as np
import pytest

import machscan
from machscan import io

pye57 = pytest.importorskip("pye57")


def quaternion_matrix(q):
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def scan(rng, n, invalid):
    """A scan as pye57 writes it, in metres, `invalid` points marked invalid (pye57 writes the
    Cartesian fields only; spherical scans are tested in the core, io/e57.rs)."""
    xyz = rng.uniform(-2.0, 2.0, (n, 3))
    state = np.zeros(n, np.int8)
    state[rng.choice(n, invalid, replace=False)] = 1
    return {
        "cartesianX": xyz[:, 0], "cartesianY": xyz[:, 1], "cartesianZ": xyz[:, 2],
        "cartesianInvalidState": state,
        "intensity": rng.uniform(0, 1, n).astype(np.float32),
        "colorRed": rng.integers(0, 256, n).astype(np.uint8),
        "colorGreen": rng.integers(0, 256, n).astype(np.uint8),
        "colorBlue": rng.integers(0, 256, n).astype(np.uint8),
        "rowIndex": np.arange(n, dtype=np.uint16) // 10,
        "columnIndex": np.arange(n, dtype=np.uint16) % 10,
    }


def test_reads_what_pye57_writes_scans_poses_and_invalid_points(tmp_path):
    rng = np.random.default_rng(1)
    q = np.array([0.9, 0.1, -0.3, 0.2])
    q /= np.linalg.norm(q)
    poses = [(np.array([1.0, 0, 0, 0]), np.zeros(3)), (q, np.array([10.0, -2.5, 0.75]))]
    scans = [scan(rng, 300, 7), scan(rng, 200, 0)]
    path = tmp_path / "two.e57"
    f = pye57.E57(str(path), mode="w")
    for s, (rot, t) in zip(scans, poses):
        f.write_scan_raw(s, rotation=rot, translation=t)
    f.close()

    c = io.read(path)
    assert c.dropped == 7
    expected, keep = [], []
    stored = pye57.E57(str(path))
    for i, (rot, t) in enumerate(poses):
        raw = stored.read_scan_raw(i)  # as stored (pye57 keeps coordinates in float32)
        ok = raw["cartesianInvalidState"] == 0
        xyz = np.column_stack([raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]]).astype(np.float64)[ok]
        expected.append(1000.0 * (xyz @ quaternion_matrix(rot).T + t))
        keep.append(ok)
    np.testing.assert_allclose(c.points, np.vstack(expected), rtol=0, atol=1e-9)
    for name in ("intensity", "colorRed", "colorGreen", "colorBlue", "rowIndex", "columnIndex"):
        want = np.concatenate([s[name][ok].astype(np.float64) for s, ok in zip(scans, keep)])
        np.testing.assert_array_equal(c.scalars[name], want, err_msg=name)
    np.testing.assert_array_equal(c.scalars["scan"], np.repeat([0.0, 1.0], [293, 200]))

    own = io.read(path, apply_pose=False)
    second = own.points[own.scalars["scan"] == 1]
    raw = stored.read_scan_raw(1)
    xyz = np.column_stack([raw["cartesianX"], raw["cartesianY"], raw["cartesianZ"]]).astype(np.float64)
    np.testing.assert_allclose(second, 1000.0 * xyz, rtol=0, atol=1e-9)


def test_pye57_reads_what_machscan_writes(tmp_path):
    rng = np.random.default_rng(2)
    n = 500
    pts = rng.uniform(-800.0, 800.0, (n, 3))
    scalars = {
        "intensity": rng.uniform(0, 1, n).astype(np.float32).astype(float),
        "colorRed": rng.integers(0, 256, n).astype(float),
        "colorGreen": rng.integers(0, 256, n).astype(float),
        "colorBlue": rng.integers(0, 256, n).astype(float),
        "allowance": rng.normal(0.3, 0.05, n),
    }
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    path = tmp_path / "out.e57"
    machscan.write_points(path, pts, normals, scalars=scalars)
    f = pye57.E57(str(path))
    assert f.scan_count == 1
    data = f.read_scan_raw(0, ignore_unsupported_fields=True)  # the normals and machscan extensions
    np.testing.assert_allclose(np.column_stack([data["cartesianX"], data["cartesianY"], data["cartesianZ"]]) * 1000.0,
                               pts, rtol=1e-15, atol=1e-12)
    for name in ("intensity", "colorRed", "colorGreen", "colorBlue"):
        np.testing.assert_array_equal(np.asarray(data[name], dtype=float), scalars[name], err_msg=name)
    back = io.read(path)
    np.testing.assert_allclose(back.points, pts, rtol=1e-15, atol=1e-12)
    np.testing.assert_array_equal(back.normals, normals.astype(np.float32))
    assert set(back.scalars) == {"intensity", "colorRed", "colorGreen", "colorBlue"}  # allowance: machscan's extension


def test_e57_signature_and_refusals(tmp_path):
    machscan.write_points(tmp_path / "a.e57", np.ones((3, 3)))
    (tmp_path / "a.e57").rename(tmp_path / "scan.bin")
    np.testing.assert_allclose(io.read(tmp_path / "scan.bin").points, np.ones((3, 3)), rtol=1e-15)
    (tmp_path / "bad.e57").write_bytes(b"ASTM-E57" + bytes(100))
    with pytest.raises(machscan.FileFormatError, match=r"bad\.e57"):
        io.read(tmp_path / "bad.e57")
    with pytest.raises(ValueError, match="colorRed, colorGreen and colorBlue"):
        machscan.write_points(tmp_path / "c.e57", np.zeros((2, 3)), scalars={"colorRed": [1.0, 2.0]})
    with pytest.raises(ValueError, match="triangles"):
        machscan.write_mesh(tmp_path / "m.e57", np.eye(3), [[0, 1, 2]])
