"""Point and mesh files: every shared data file against Open3D and trimesh, round trips in
float32 (the default) and float64, files machscan writes read by Open3D's legacy and tensor
readers and trimesh, byte orders, malformed files, and the exception of every failure."""

import struct
from pathlib import Path

import numpy as np
import open3d
import pytest

import machscan
from machscan import io
from paths import DATA

PCDS = ["bun0.pcd", "bun4.pcd", "bunny.pcd", "milk.pcd"]


@pytest.mark.parametrize("name", PCDS)
def test_shared_pcd_files_equal_open3d(name):
    path = DATA / "pcl-bunny-icp" / name
    got = io.read(path)
    ref = open3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(got.points, np.asarray(ref.points))
    if ref.has_normals():
        np.testing.assert_array_equal(got.normals, np.asarray(ref.normals))
    np.testing.assert_array_equal(machscan.read_points(path), got.points)


def test_bun0_curvature_is_read_by_name():
    c = io.read(DATA / "pcl-bunny-icp" / "bun0.pcd")
    assert c.normals is not None and "curvature" in c.scalars and len(c.scalars["curvature"]) == 397


def test_stanford_bunny_mesh_equals_open3d():
    path = DATA / "stanford-bunny-mesh" / "stanford_bunny.ply"
    c = io.read(path)
    m = open3d.io.read_triangle_mesh(str(path))
    np.testing.assert_array_equal(c.points, np.asarray(m.vertices))
    np.testing.assert_array_equal(c.triangles, np.asarray(m.triangles))
    assert set(c.scalars) == {"confidence", "intensity"}


@pytest.mark.parametrize("binary", [True, False])
def test_ply_float64_round_trip_is_exact(tmp_path, binary):
    rng = np.random.default_rng(0)
    p = rng.normal(0, 1000, (500, 3))  # machine coordinates, full double precision
    n = rng.normal(size=(500, 3))
    a = rng.normal(size=500)
    path = tmp_path / "c.ply"
    machscan.write_points(path, p, n, binary=binary, scalars={"allowance": a}, dtype="float64")
    c = io.read(path)
    np.testing.assert_array_equal(c.points, p)
    np.testing.assert_array_equal(c.normals, n)
    np.testing.assert_array_equal(c.scalars["allowance"], a)
    ref = open3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(np.asarray(ref.points), p)


WRITES = [
    ("ply", dict(binary=True)),
    ("ply", dict(binary=False)),
    ("pcd", dict(binary=True)),
    ("pcd", dict(binary=False)),
    ("pcd", dict(compressed=True)),
]


@pytest.mark.parametrize("ext, kw", WRITES)
def test_default_files_open_in_open3d_legacy_and_tensor_readers(tmp_path, ext, kw):
    """The defaults are float32 fields, which both Open3D readers take (the legacy PCD reader
    reads 8-byte coordinates as zeros); the values are the float32 of the points."""
    rng = np.random.default_rng(1)
    p = rng.normal(0, 800, (400, 3))
    n = rng.normal(size=(400, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    path = tmp_path / f"d.{ext}"
    machscan.write_points(path, p, n, scalars={"frame": np.arange(400.0)}, **kw)
    f32 = p.astype(np.float32)
    # ASCII holds the shortest decimal of each float32, which double readers parse as written.
    text = kw.get("binary") is False
    expect = f32.astype(str).astype(np.float64) if text else f32.astype(np.float64)
    legacy = open3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(np.asarray(legacy.points), expect)
    np.testing.assert_array_equal(
        np.asarray(legacy.normals), n.astype(np.float32).astype(str).astype(np.float64) if text else n.astype(np.float32)
    )
    tensor = open3d.t.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(tensor.point.positions.numpy(), f32)
    np.testing.assert_array_equal(tensor.point.frame.numpy().ravel(), np.arange(400.0))
    np.testing.assert_array_equal(io.read(path).points, expect)


@pytest.mark.parametrize("ext, kw", WRITES)
def test_float64_is_kept_when_asked(tmp_path, ext, kw):
    p = np.random.default_rng(2).normal(0, 1500, (300, 3))
    path = tmp_path / f"e.{ext}"
    machscan.write_points(path, p, dtype="float64", **kw)
    np.testing.assert_array_equal(io.read(path).points, p)
    np.testing.assert_array_equal(open3d.t.io.read_point_cloud(str(path)).point.positions.numpy(), p)


def _ply(path, fmt, header_props, rows_bytes_or_text, n, faces=None):
    head = f"ply\nformat {fmt} 1.0\nelement vertex {n}\n" + "".join(f"property {t} {name}\n" for t, name in header_props)
    if faces is not None:
        head += f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
    head += "end_header\n"
    with open(path, "wb") as fh:
        fh.write(head.encode())
        fh.write(rows_bytes_or_text)
        if faces is not None:
            for f in faces:
                fh.write(f if isinstance(f, bytes) else f.encode())


@pytest.mark.parametrize("order", [">", "<"])
def test_binary_ply_float32_both_byte_orders_with_faces(tmp_path, order):
    p = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5]], dtype=np.float32)
    q = np.arange(4, dtype=np.uint8)
    rec = np.zeros(4, dtype=[("x", order + "f4"), ("y", order + "f4"), ("z", order + "f4"), ("q", "u1")])
    rec["x"], rec["y"], rec["z"], rec["q"] = p[:, 0], p[:, 1], p[:, 2], q
    fmt = "binary_big_endian" if order == ">" else "binary_little_endian"
    quad = struct.pack(order + "B4i", 4, 0, 1, 2, 3)
    path = tmp_path / "m.ply"
    _ply(path, fmt, [("float", "x"), ("float", "y"), ("float", "z"), ("uchar", "q")], rec.tobytes(), 4, faces=[quad])
    c = io.read(path)
    np.testing.assert_array_equal(c.points, p.astype(np.float64))
    np.testing.assert_array_equal(c.scalars["q"], q)
    np.testing.assert_array_equal(c.triangles, [[0, 1, 2], [0, 2, 3]])


def _pcd_header(fields, sizes, types, n, data):
    return (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
        f"FIELDS {' '.join(fields)}\nSIZE {' '.join(map(str, sizes))}\nTYPE {' '.join(types)}\n"
        f"COUNT {' '.join('1' for _ in fields)}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n"
    ).encode()


def _lzf_literal(raw: bytes) -> bytes:
    out = bytearray()
    for k in range(0, len(raw), 32):
        chunk = raw[k : k + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


@pytest.mark.parametrize("data", ["ascii", "binary", "binary_compressed"])
def test_pcd_layouts_equal_open3d(tmp_path, data):
    rng = np.random.default_rng(1)
    n = 257
    p = rng.normal(size=(n, 3)).astype(np.float32)
    inten = rng.uniform(0, 1, n).astype(np.float32)
    fields, sizes, types = ["x", "y", "z", "intensity"], [4, 4, 4, 4], ["F", "F", "F", "F"]
    cols = [p[:, 0], p[:, 1], p[:, 2], inten]
    path = tmp_path / f"c_{data}.pcd"
    with open(path, "wb") as fh:
        fh.write(_pcd_header(fields, sizes, types, n, data))
        if data == "ascii":
            fh.write("".join(" ".join(repr(float(c[i])) for c in cols) + "\n" for i in range(n)).encode())
        elif data == "binary":
            fh.write(np.column_stack(cols).astype("<f4").tobytes())
        else:
            raw = b"".join(c.astype("<f4").tobytes() for c in cols)  # column-major
            comp = _lzf_literal(raw)
            fh.write(struct.pack("<II", len(comp), len(raw)) + comp)
    c = io.read(path)
    np.testing.assert_array_equal(c.points, p.astype(np.float64))
    np.testing.assert_array_equal(c.scalars["intensity"], inten.astype(np.float64))
    ref = open3d.io.read_point_cloud(str(path))
    np.testing.assert_array_equal(np.asarray(ref.points), c.points)


def test_text_points_with_header_and_columns(tmp_path):
    (tmp_path / "a.csv").write_text("id,x,y,z\n0,1.5,2,3\n1,4,5,6e-3\n")
    got = io.read(tmp_path / "a.csv", columns=(1, 2, 3))
    np.testing.assert_array_equal(got.points, [[1.5, 2, 3], [4, 5, 6e-3]])
    (tmp_path / "b.xyz").write_text("# comment\n1 2 3\n4 5 6\n")
    np.testing.assert_array_equal(machscan.read_points(tmp_path / "b.xyz"), [[1, 2, 3], [4, 5, 6]])


def _write(path, content):
    with open(path, "wb") as fh:
        fh.write(content)


def bad_files(tmp_path):
    hdr = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n"
    )
    yield "truncated.ply", hdr + b"\0" * 50, "truncated"
    yield (
        "liar.ply",
        (b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n"),
        "declares 5 vertices",
    )
    yield "type.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n1\n", "unknown property type"
    yield "noend.ply", b"ply\nformat ascii 1.0\nelement vertex 1\n", "end_header"
    yield "noxyz.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n", "x, y and z"
    yield (
        "face.ply",
        (
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            b"element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            b"0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"
        ),
        "vertex 7",
    )
    yield "notnum.pcd", _pcd_header(["x", "y", "z"], [4, 4, 4], ["F", "F", "F"], 2, "ascii") + b"1 2 3\n4 x 6\n", "not a number"
    yield "short.pcd", _pcd_header(["x", "y", "z"], [4, 4, 4], ["F", "F", "F"], 9, "binary") + b"\0" * 20, "truncated"
    raw = np.zeros(12, "<f4").tobytes()
    lzf = _pcd_header(["x", "y", "z"], [4, 4, 4], ["F", "F", "F"], 4, "binary_compressed")
    yield "lzf.pcd", lzf + struct.pack("<II", 3, len(raw)) + b"\x05ab", "LZF"
    yield "type.pcd", _pcd_header(["x", "y", "z"], [4, 4, 3], ["F", "F", "F"], 1, "ascii") + b"1 2 3\n", "not a number type"


def test_malformed_files_name_the_file_and_the_problem(tmp_path):
    for name, content, msg in bad_files(tmp_path):
        path = tmp_path / name
        _write(path, content)
        with pytest.raises(ValueError) as exc:
            io.read(path)
        assert name in str(exc.value) and msg in str(exc.value), (name, str(exc.value))


def test_each_failure_raises_its_exception_naming_the_file(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        io.read("/nonexistent/cloud.ply")
    assert e.value.filename == "/nonexistent/cloud.ply" and e.value.errno == 2
    (tmp_path / "dir.ply").mkdir()
    with pytest.raises(IsADirectoryError):
        io.read(tmp_path / "dir.ply")
    if Path("/sys").is_dir():  # sysfs refuses new files, even to root
        with pytest.raises(PermissionError):
            machscan.write_points("/sys/machscan-test.ply", np.zeros((2, 3)))
    with pytest.raises(FileNotFoundError):
        machscan.write_points(tmp_path / "no" / "such" / "dir.ply", np.zeros((2, 3)))
    (tmp_path / "bad.pcd").write_text("VERSION 0.7\nFIELDS x y\n")
    with pytest.raises(machscan.FileFormatError) as e:
        io.read(tmp_path / "bad.pcd")
    assert isinstance(e.value, ValueError) and e.value.filename == str(tmp_path / "bad.pcd")
    assert str(tmp_path / "bad.pcd") in str(e.value)


def test_unknown_extensions_list_every_format():
    with pytest.raises(ValueError) as e:
        io.read("cloud.foo")
    assert all(f".{ext}" in str(e.value) for ext in io.READ_FORMATS)
    assert {"ply", "pcd", "stl", "obj", "xyz", "csv", "txt", "pts", "asc", "las", "laz", "e57"} == set(io.READ_FORMATS)
    with pytest.raises(ValueError) as e:
        machscan.write_points("cloud.foo", np.zeros((1, 3)))
    listed = str(e.value).split("writes")[1]
    assert all(f".{ext}" in listed for ext in io.WRITE_FORMATS) and set(io.WRITE_FORMATS) == set(io.READ_FORMATS)


@pytest.mark.parametrize(
    "call, arg",
    [
        (lambda p: machscan.write_points(p / "a.ply", np.zeros((2, 3)), compressed=True), "compressed"),
        (lambda p: machscan.write_points(p / "a.pcd", np.zeros((2, 3)), binary=False, compressed=True), "compressed"),
        (lambda p: machscan.write_points(p / "a.ply", np.zeros((2, 3)), scalars={"x": [1, 2]}), "scalars"),
        (lambda p: machscan.write_points(p / "a.pcd", np.zeros((2, 3)), scalars={"normal_x": [1, 2]}), "scalars"),
        (lambda p: machscan.write_points(p / "a.ply", np.zeros((2, 3)), scalars={"a b": [1, 2]}), "scalars"),
        (lambda p: machscan.write_points(p / "a.xyz", np.zeros((2, 3)), binary=True), "binary"),
        (lambda p: machscan.write_points(p / "a.ply", np.zeros((2, 3)), dtype="float16"), "dtype"),
        (lambda p: machscan.write_mesh(p / "a.stl", np.zeros((3, 3)), [[0, 1, 2]], dtype="float64"), "dtype"),
        (lambda p: machscan.write_mesh(p / "a.pcd", np.zeros((3, 3)), [[0, 1, 2]]), "triangles"),
        (lambda p: machscan.write_mesh(p / "a.ply", np.zeros((3, 3)), [[0, 1, 3]]), "triangles"),
        (lambda p: machscan.write_mesh(p / "a.ply", np.zeros((3, 3)), [[0, 1, 1.5]]), "triangles"),
    ],
)
def test_contradictory_options_and_reserved_names_raise(tmp_path, call, arg):
    with pytest.raises(ValueError) as e:
        call(tmp_path)
    assert str(e.value).startswith(arg), str(e.value)
    assert not any(tmp_path.iterdir()), "nothing is written when a call is refused"


def test_select_carries_normals_scalars_and_triangles(tmp_path):
    m = io.read(DATA / "stanford-bunny-mesh" / "stanford_bunny.ply")
    keep = machscan.remove_statistical_outliers(m.points, 20, 1.0)
    sub = m.select(keep)
    np.testing.assert_array_equal(sub.points, m.points[keep])
    np.testing.assert_array_equal(sub.scalars["intensity"], m.scalars["intensity"][keep])
    kept = np.zeros(len(m.points), bool)
    kept[keep] = True
    whole = m.triangles[kept[m.triangles].all(axis=1)]
    np.testing.assert_array_equal(keep[sub.triangles], whole)
    c = io.read(DATA / "pcl-bunny-icp" / "bun0.pcd").select(np.arange(397) % 2 == 0)
    assert len(c) == 199 and c.normals.shape == (199, 3) and c.scalars["curvature"].shape == (199,)
    with pytest.raises(ValueError, match="index"):
        c.select(np.ones(5, bool))


@pytest.mark.parametrize(
    "ext, kw",
    [
        ("pcd", dict(binary=True)),
        ("pcd", dict(binary=False)),
        ("pcd", dict(compressed=True)),
        ("xyz", {}),
        ("csv", {}),
        ("ply", dict(binary=False)),
    ],
)
def test_every_writer_round_trips_in_float64(tmp_path, ext, kw):
    rng = np.random.default_rng(5)
    p = rng.normal(0, 1500, (300, 3))
    n = rng.normal(size=(300, 3))
    s = rng.normal(size=300)
    path = tmp_path / f"c.{ext}"
    rich = ext in ("pcd", "ply")
    kw = dict(kw, dtype="float64") if rich else kw  # text formats are full precision by default
    machscan.write_points(path, p, n if rich else None, scalars={"allowance": s} if rich else None, **kw)
    c = io.read(path)
    np.testing.assert_array_equal(c.points, p)  # binary exact; text written as shortest round-trip
    if rich:
        np.testing.assert_array_equal(c.normals, n)
        np.testing.assert_array_equal(c.scalars["allowance"], s)
    if ext in ("ply", "xyz"):  # Open3D's legacy reader reads no CSV (and PCD doubles as 0)
        np.testing.assert_array_equal(np.asarray(open3d.io.read_point_cloud(str(path)).points), p)


def test_text_files_refuse_normals(tmp_path):
    with pytest.raises(ValueError, match="normals"):
        machscan.write_points(tmp_path / "a.xyz", np.zeros((2, 3)), np.zeros((2, 3)))


def test_toolpath_round_trip(tmp_path):
    rng = np.random.default_rng(9)
    p = rng.normal(0, 100, (50, 3))
    a = rng.normal(size=(50, 3))
    f = np.repeat([1200.0, 800.0], 25)
    seg = np.repeat([0, 1, 2], [10, 20, 20])
    io.write_toolpath(tmp_path / "t.cl", p, a, f, seg)
    with pytest.raises(ValueError, match=r"^points"):
        io.write_toolpath(tmp_path / "u.cl", np.full((2, 3), np.nan))
    tp = io.read_toolpath(tmp_path / "t.cl")
    np.testing.assert_array_equal(tp.points, p)
    np.testing.assert_array_equal(tp.axes, a)
    np.testing.assert_array_equal(tp.feeds, f)
    np.testing.assert_array_equal(tp.segments, seg)
    text = (tmp_path / "t.cl").read_text()
    assert text.count("FEDRAT") == 2 and text.count("RAPID") == 2


def test_toolpath_errors_name_file_and_line(tmp_path):
    (tmp_path / "b.apt").write_text("PARTNO/X" + chr(10) + "GOTO/1,2,oops" + chr(10))
    with pytest.raises(ValueError, match=r"b[.]apt: line 2"):
        io.read_toolpath(tmp_path / "b.apt")
    # Numbers Rust and Python would read, but no machine can go to.
    for k, text in enumerate(["GOTO/1,2,nan", "GOTO/inf,0,3", "GOTO/1,2,3,0,0,1e400", "FEDRAT/-5\nGOTO/1,1,1"]):
        (tmp_path / f"n{k}.apt").write_text("PARTNO/X\n" + text + "\n")
        with pytest.raises(ValueError, match=rf"n{k}[.]apt: line 2"):
            io.read_toolpath(tmp_path / f"n{k}.apt")
    pts = np.zeros((3, 3))
    for feeds in ([-1.0, 5.0, 5.0], [5.0, np.inf, 5.0], [5.0, np.nan, 5.0]):
        with pytest.raises(ValueError, match="feeds"):
            io.write_toolpath(tmp_path / "f.cl", pts, feeds=feeds)
    io.write_toolpath(tmp_path / "f.cl", pts, feeds=[np.nan, 5.0, 5.0])  # no feed before the first: as read
    assert np.isnan(io.read_toolpath(tmp_path / "f.cl").feeds[0])


@pytest.mark.parametrize("name, nv, nf", [("flat_triangular_mesh.txt", 121, 200), ("hedgehog_mesh.txt", 300, 596)])
def test_geodesic_test_meshes_read(name, nv, nf):
    c = io.read(DATA / "geodesic-flat-mesh" / name)
    assert c.points.shape == (nv, 3) and c.triangles.shape == (nf, 3)
    assert c.triangles.max() < nv
    if name.startswith("flat"):
        # The README's check: the 11 × 11 grid over [1.5, 3.5] × [-1, 1], z = 0, and
        # |v25 − v97| = 1.2·√2.
        assert np.allclose(c.points[:, 2], 0) and c.points[:, 0].min() == 1.5 and c.points[:, 1].max() == 1.0
        assert np.linalg.norm(c.points[25] - c.points[97]) == pytest.approx(1.697056274847714, abs=1e-12)


def test_mesh_txt_that_lies_is_an_error(tmp_path):
    (tmp_path / "m.txt").write_text("3 1" + chr(10) + "0 0 0" + chr(10) + "1 0 0" + chr(10))
    with pytest.raises(ValueError, match=r"m\.txt"):
        io.read(tmp_path / "m.txt")


BUNNY = DATA / "stanford-bunny-mesh" / "stanford_bunny.ply"


def _corners(vertices, triangles):
    """The corner coordinates of every triangle in file order, ``(T, 3, 3)``: the same mesh
    whatever the vertex numbering (every reader here keeps the order of the faces)."""
    return np.asarray(vertices)[np.asarray(triangles)]


@pytest.mark.parametrize(
    "name, kw", [("b.stl", {}), ("b.stl", dict(binary=False)), ("b.obj", {}), ("b.ply", {}), ("b.ply", dict(binary=False))]
)
def test_meshes_machscan_writes_read_equal_in_trimesh_open3d_and_machscan(tmp_path, name, kw):
    import trimesh

    mesh = io.read_mesh(BUNNY)
    path = tmp_path / name
    machscan.write_mesh(path, mesh.vertices, mesh.triangles, **kw)
    # Values as the file stores them: float32 (STL, PLY by default) or full precision (OBJ). An
    # ASCII file holds the shortest decimal of each float32, which rounds back to it.
    dtype = np.float64 if name.endswith("obj") else np.float32
    expect = _corners(mesh.vertices, mesh.triangles).astype(dtype)
    ours = io.read_mesh(path)
    theirs = trimesh.load(path, process=False, force="mesh")
    np.testing.assert_array_equal(_corners(ours.vertices, ours.triangles).astype(dtype), expect)
    np.testing.assert_array_equal(_corners(theirs.vertices, theirs.faces).astype(dtype), expect)
    # Open3D parses ASCII STL and OBJ in float32 arithmetic, up to an ulp off.
    o3d = open3d.io.read_triangle_mesh(str(path))
    np.testing.assert_allclose(_corners(o3d.vertices, o3d.triangles), expect, rtol=2.5e-7, atol=0)
    # STL keeps the vertices the faces use, one per distinct coordinate triple.
    n_stl = len(np.unique(mesh.vertices[np.unique(mesh.triangles)].astype(np.float32), axis=0))
    assert len(ours.vertices) == (n_stl if name.endswith("stl") else len(mesh.vertices))


def test_stl_and_obj_read_equal_to_trimesh_on_files_trimesh_writes(tmp_path):
    import trimesh

    mesh = io.read_mesh(BUNNY)
    tm = trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False)
    for name in ("t.stl", "t.obj"):
        tm.export(tmp_path / name)
        ours = io.read_mesh(tmp_path / name)
        ref = trimesh.load(tmp_path / name, force="mesh", process=False)
        np.testing.assert_array_equal(_corners(ours.vertices, ours.triangles), _corners(ref.vertices, ref.faces))
    # trimesh's processed STL merges equal corners into one vertex, as machscan does.
    merged = trimesh.load(tmp_path / "t.stl", force="mesh")
    assert len(io.read_mesh(tmp_path / "t.stl").vertices) == len(merged.vertices)


def test_read_mesh_refuses_a_point_cloud():
    with pytest.raises(machscan.FileFormatError, match="no faces"):
        io.read_mesh(DATA / "pcl-bunny-icp" / "bun0.pcd")
