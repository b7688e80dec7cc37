"""LAS and LAZ files against laspy (+ lazrs) on the same files, each library reading what the
other writes (issue #34 §1)."""

from __future__ import annotations

import numpy as np
import pytest

import machscan
from machscan import io

laspy = pytest.importorskip("laspy")

# Point formats and the LAS version that holds them (6–8 need 1.4).
FORMATS = [(0, "1.2"), (1, "1.2"), (2, "1.2"), (3, "1.2"), (6, "1.4"), (7, "1.4"), (8, "1.4")]


def laspy_file(path, point_format, version, rng, n=500):
    """A file laspy writes: every point field random within its range, and extra bytes of
    several types, one scaled and offset, one a three-element array."""
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales = [0.001, 0.0005, 0.00025]
    header.offsets = [1000.0, -250.0, 12.5]
    header.add_extra_dims(
        [
            laspy.ExtraBytesParams("allowance", "f8"),
            laspy.ExtraBytesParams("quality", "u1"),
            laspy.ExtraBytesParams("height", "i2", scales=np.array([0.01]), offsets=np.array([5.0])),
            laspy.ExtraBytesParams("weight", "f4"),
            laspy.ExtraBytesParams("direction", "3f8"),
        ]
    )
    las = laspy.LasData(header)
    las.x = 1000.0 + rng.uniform(0, 200, n)
    las.y = -250.0 + rng.uniform(0, 100, n)
    las.z = 12.5 + rng.uniform(0, 50, n)
    for dim in las.point_format.dimensions:
        name = dim.name
        if name in ("X", "Y", "Z") or name in ("allowance", "quality", "height", "weight", "direction"):
            continue
        dtype = np.dtype(dim.dtype) if dim.dtype is not None else None
        if name == "gps_time":
            las[name] = rng.uniform(0, 1e6, n)
        elif name in ("return_number", "number_of_returns"):
            las[name] = rng.integers(1, 8 if point_format < 6 else 16, n)
        elif name == "classification":
            las[name] = rng.integers(0, 32 if point_format < 6 else 256, n)
        elif name == "scan_angle_rank":
            las[name] = rng.integers(-90, 91, n)
        elif name == "scan_angle":
            las[name] = rng.integers(-30000, 30001, n)
        elif name == "scanner_channel":
            las[name] = rng.integers(0, 4, n)
        elif dim.num_bits == 1:
            las[name] = rng.integers(0, 2, n)
        elif dtype is not None and dtype.kind == "u":
            las[name] = rng.integers(0, np.iinfo(dtype).max, n, endpoint=True)
    las.allowance = rng.normal(0.3, 0.05, n)
    las.quality = rng.integers(0, 256, n)
    las.height = 5.0 + 0.01 * rng.integers(-3000, 3000, n)
    las.weight = rng.uniform(0, 1, n).astype(np.float32)
    las.direction = rng.normal(size=(n, 3))
    las.write(path)
    return laspy.read(path)


@pytest.mark.parametrize("point_format, version", FORMATS)
@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_reads_what_laspy_writes(tmp_path, point_format, version, suffix):
    path = tmp_path / f"pf{point_format}{suffix}"
    ref = laspy_file(path, point_format, version, np.random.default_rng(point_format))
    c = io.read(path)
    # Coordinates X·scale + offset in float64: the same operations, so the same bits.
    np.testing.assert_array_equal(c.points, np.column_stack([ref.x, ref.y, ref.z]))
    names = [d for d in ref.point_format.dimension_names if d not in ("X", "Y", "Z")]
    for name in names:
        values = np.asarray(ref[name], dtype=np.float64)
        if values.ndim == 2:
            for k in range(values.shape[1]):
                np.testing.assert_array_equal(c.scalars[f"{name}_{k}"], values[:, k], err_msg=f"{name}_{k}")
        else:
            np.testing.assert_array_equal(c.scalars[name], values, err_msg=name)
    expected = {n for n in names if np.asarray(ref[n]).ndim == 1} | {f"direction_{k}" for k in range(3)}
    assert set(c.scalars) == expected
    assert c.normals is None and c.triangles.shape == (0, 3)


@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_laspy_reads_what_machscan_writes(tmp_path, suffix):
    rng = np.random.default_rng(3)
    n = 1000
    pts = rng.uniform(-300.0, 300.0, (n, 3))
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    scalars = {
        "intensity": rng.integers(0, 65536, n).astype(float),
        "classification": rng.integers(0, 12, n).astype(float),
        "gps_time": rng.uniform(0, 1e5, n),
        "red": rng.integers(0, 65536, n).astype(float),
        "green": rng.integers(0, 65536, n).astype(float),
        "blue": rng.integers(0, 65536, n).astype(float),
        "scan_angle": rng.integers(-30000, 30001, n).astype(float),
        "allowance": rng.normal(0.3, 0.05, n),
    }
    path = tmp_path / f"out{suffix}"
    machscan.write_points(path, pts, normals, scalars=scalars)
    ref = laspy.read(path)
    assert ref.header.version.minor == 4 and ref.header.point_format.id == 7
    assert (suffix == ".laz") == ref.header.are_points_compressed
    xyz = np.column_stack([ref.x, ref.y, ref.z])
    assert np.abs(xyz - pts).max() <= 0.5 * 1e-4 + 1e-9  # the default step, 0.1 µm
    back = io.read(path)
    np.testing.assert_array_equal(back.points, xyz)
    np.testing.assert_array_equal(back.normals, normals)
    for name, values in scalars.items():
        np.testing.assert_array_equal(np.asarray(ref[name], dtype=np.float64), values, err_msg=name)
        np.testing.assert_array_equal(back.scalars[name], values, err_msg=name)
    np.testing.assert_array_equal(np.column_stack([ref.normal_x, ref.normal_y, ref.normal_z]), normals)


def test_scale_and_float32_extra_bytes(tmp_path):
    pts = np.array([[0.0, 0.0, 0.0], [1234.56789, -0.001, 7.0]])
    machscan.write_points(tmp_path / "a.las", pts, scalars={"a": [0.1, 0.2]}, scale=0.01, dtype="float32")
    ref = laspy.read(tmp_path / "a.las")
    np.testing.assert_array_equal(ref.header.scales, [0.01] * 3)
    np.testing.assert_allclose(np.column_stack([ref.x, ref.y, ref.z]), pts, atol=0.005 + 1e-9)
    assert ref.point_format.dimension_by_name("a").dtype == np.float32
    np.testing.assert_array_equal(io.read(tmp_path / "a.las").scalars["a"], np.float32([0.1, 0.2]))


def test_files_are_read_by_their_signature(tmp_path):
    pts = np.random.default_rng(0).uniform(0, 10, (50, 3))
    machscan.write_points(tmp_path / "a.laz", pts)
    (tmp_path / "a.laz").rename(tmp_path / "named-las.las")
    np.testing.assert_allclose(io.read(tmp_path / "named-las.las").points, pts, atol=1e-4)
    machscan.write_points(tmp_path / "b.las", pts)
    (tmp_path / "b.las").rename(tmp_path / "scan.dat")
    np.testing.assert_allclose(io.read(tmp_path / "scan.dat").points, pts, atol=1e-4)


def test_bad_files_and_arguments(tmp_path):
    (tmp_path / "bad.las").write_bytes(b"LASF but not really")
    with pytest.raises(machscan.FileFormatError, match=r"bad\.las"):
        io.read(tmp_path / "bad.las")
    machscan.write_points(tmp_path / "a.laz", np.zeros((5000, 3)) + np.arange(5000)[:, None])
    data = (tmp_path / "a.laz").read_bytes()
    (tmp_path / "cut.laz").write_bytes(data[: len(data) // 2])
    with pytest.raises(machscan.FileFormatError, match=r"cut\.laz"):
        io.read(tmp_path / "cut.laz")
    with pytest.raises(ValueError, match="scale"):
        machscan.write_points(tmp_path / "a.ply", np.zeros((1, 3)), scale=0.01)
    with pytest.raises(ValueError, match="scale"):
        machscan.write_points(tmp_path / "a.las", np.array([[0.0, 0, 0], [1e6, 0, 0]]))
    with pytest.raises(ValueError, match="intensity"):
        machscan.write_points(tmp_path / "a.las", np.zeros((2, 3)), scalars={"intensity": [1.5, 2.0]})
    with pytest.raises(ValueError, match="red, green and blue"):
        machscan.write_points(tmp_path / "a.las", np.zeros((2, 3)), scalars={"red": [1.0, 2.0]})
    with pytest.raises(ValueError, match="compressed"):
        machscan.write_points(tmp_path / "a.las", np.zeros((2, 3)), compressed=True)
