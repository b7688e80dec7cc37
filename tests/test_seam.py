"""The seam between Python and the Rust core: arrays in whatever form NumPy hands over, the one
error mapping, typed results, the GIL released while kernels run."""

import ast
import inspect
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import machscan
from machscan import _core
from paths import DATA

STUB = Path(machscan.__file__).with_name("_core.pyi")


def misaligned(a):
    """The same values at an odd byte offset, as np.frombuffer, shared memory and Dask workers
    hand them over."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    buf = np.zeros(a.nbytes + 1, dtype=np.uint8)
    out = np.frombuffer(buf.data, dtype=np.float64, offset=1, count=a.size).reshape(a.shape)
    out[...] = a
    assert not out.flags.aligned and out.flags.c_contiguous
    return out


def forms(a):
    """Array forms a plant script passes: misaligned, big-endian, Fortran order, a strided view,
    integers, read-only, a nested list."""
    a = np.asarray(a, dtype=np.float64)
    strided = np.zeros((a.shape[0], 2 * a.shape[1]))[:, ::2]
    strided[...] = a
    readonly = a.copy()
    readonly.flags.writeable = False
    yield "misaligned", misaligned(a)
    yield "big-endian", a.astype(">f8")
    yield "fortran", np.asfortranarray(a)
    yield "strided", strided
    yield "readonly", readonly
    yield "list", a.tolist()


P = np.random.default_rng(0).normal(0, 10, (2000, 3)).round(3)


@pytest.mark.parametrize(
    "call",
    [
        lambda p: machscan.voxel_downsample(p, 2.0),
        lambda p: machscan.remove_statistical_outliers(p, 10, 2.0),
        lambda p: machscan.estimate_normals(p, k=10),
        lambda p: machscan.knn_graph(p, 5)[0],
        lambda p: machscan.crop_box(p, (-5, -5, -5), (5, 5, 5)),
        lambda p: machscan.euclidean_clusters(p, 1.5),
    ],
    ids=["voxel", "sor", "normals", "knn", "crop", "clusters"],
)
def test_every_array_form_gives_the_same_answer(call):
    ref = call(P)
    for name, p in forms(P):
        np.testing.assert_array_equal(call(p), ref, err_msg=name)


def test_groove_fit_takes_a_misaligned_frame_block():
    x = (np.arange(200) - 100) * 0.025
    z = np.where(np.abs(x) < 0.25, -0.3, 0.0) + np.random.default_rng(1).normal(0, 0.008, (50, 200))
    ref = machscan.fit_grooves(x, z, window=200)
    got = machscan.fit_grooves(misaligned(x), misaligned(z), window=200)
    np.testing.assert_array_equal(got.width, ref.width)
    np.testing.assert_array_equal(got.status, ref.status)


@pytest.mark.parametrize(
    "bad, says",
    [
        ([["a", "b", "c"]], "dtype <U1"),
        ([[1 + 2j, 0, 0]], "dtype complex128"),
        ([[1, 2, 3], [4, 5]], "cannot be converted"),
        (np.zeros((4, 2)), r"expected shape \(N, 3\), got \(4, 2\)"),
        (None, "got None"),
    ],
)
def test_what_is_not_points_is_refused_naming_the_argument(bad, says):
    with pytest.raises(ValueError, match=r"^points: .*" + says):
        machscan.voxel_downsample(bad, 1.0)


def _typed_dicts():
    """The TypedDicts of the stub, by name, with their keys."""
    tree = ast.parse(STUB.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and any(getattr(b, "id", "") == "TypedDict" for b in node.bases):
            out[node.name] = [n.target.id for n in node.body if isinstance(n, ast.AnnAssign)]
    return out


def _table(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("x,y\n1,2\n")
    return path


def test_dict_results_have_exactly_the_keys_their_typed_dict_declares(tmp_path):
    declared = _typed_dicts()
    x = (np.arange(64) - 32) * 0.025
    z = np.where(np.abs(x) < 0.25, -0.3, 0.0)[None, :]
    options = machscan.GrooveOptions()
    path = tmp_path / "t.apt"
    path.write_text("GOTO/1,2,3\n")
    scs = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1.0]])
    # A Fibonacci sphere, and an ellipsoid whose normals fix a probe pose.
    i = np.arange(200) + 0.5
    h = 1 - 2 * i / 200
    unit = np.column_stack([np.sqrt(1 - h * h) * np.cos(2.4 * i), np.sqrt(1 - h * h) * np.sin(2.4 * i), h])
    # A flat 7 × 7 grid, for the mesh-based kernels.
    grid = np.column_stack([np.arange(49) % 7, np.arange(49) // 7, np.zeros(49)]).astype(float)
    results = {
        "_GrooveFitArrays": _core.fit_grooves(x, z, options),
        "_FrameViewArrays": _core.view_groove_frame(x, z[0], options),
        "_GrooveOptions": _core.groove_defaults(),
        "_CriteriaDefaults": _core.fit_criteria_defaults(),
        "_Criteria": _core.fit_criteria_defaults()["tanh"],
        "_ContourErrorArrays": _core.contour_error(P[:10], P[:12]),
        "_BendingSurfaceArrays": _core.fit_bending_surface(P[:, 0], P[:, 1], P[:, 2], degree=2),
        "_TableArrays": _core.read_table(_table(tmp_path), name="t"),
        "_CloudArrays": _core.read_cloud(DATA / "pcl-bunny-icp/bun0.pcd"),
        "_ToolpathArrays": _core.read_toolpath(path),
        "_MountCalibrationArrays": _core.calibrate_mount(scs, scs + 1.0),
        "_IcpArrays": _core.icp(
            P[:50],
            P[:60],
            1.0,
            init=None,
            target_normals=None,
            method="point_to_point",
            max_iterations=3,
            relative_fitness=0.0,
            relative_rmse=0.0,
            robust=None,
            robust_scale=None,
            trim=0.0,
            mse_threshold=None,
        ),
        "_IcpDefaults": _core.icp_defaults(),
        "_ProbeFitArrays": _core.probe_fit(
            unit * [10, 20, 30], unit * [10, 20, 30], unit / [10, 20, 30], probe_radius=0.0, init=None
        ),
        "_ClosestArrays": _core.closest_points(scs[:3], [[0, 1, 2]], scs),
        "_InsertedArrays": _core.insert_points(scs[:3], [[0, 1, 2]], scs[:1], tolerance=1e-6),
        "_IsometricMatchArrays": _core.isometric_match(
            grid,
            None,
            grid,
            None,
            grid[[0, -1]],
            grid[[0, -1]],
            grid[[11, 13, 15, 25, 27, 29, 38, 40]],
            None,
            jacobian="gradient",
            method="fmm",
            spacing="auto",
            max_edge=None,
            max_iterations=1,
            tolerance=1e-3,
        ),
        "_CompensatedArrays": _core.compensate_toolpath(
            grid[:5], grid, grid, grid, None, interpolation="cubic", normals="smooth", radius=None, max_edge=None
        ),
        "_BeadChainArrays": _core.bead_chain(grid, None, None, method="tree"),
        "_GrindingPathArrays": _core.grinding_paths(
            grid,
            np.tile([0.0, 0.0, 1.0], (49, 1)),
            np.full(49, 0.2),
            tool_radius=5.0,
            scallop_height=0.01,
            section_normal=[0.0, 1.0, 0.0],
            thickness=None,
            spacing=None,
            tolerance=None,
            fit_radius=None,
            removal=(0.05, (0.6, -0.7, 0.8), 20.0, 15.0, (0.5, 200.0)),
            feed_step=None,
        ),
        "_RemovalArrays": _core.simulate_removal(
            grid,
            np.tile([0.0, 0.0, 1.0], (49, 1)),
            np.full(49, 0.2),
            grid[:7],
            np.tile([0.0, 0.0, 1.0], (7, 1)),
            np.full(7, 0.2),
            [0] * 7,
            np.full(7, 0.2),
            tool_radius=5.0,
        ),
        "_EnvelopeFitArrays": _core.envelope_fit(
            10 * unit, unit, 10.5 * unit, min_allowance=0.0, surface="quadric", k=None, spacing=None, init=None
        ),
    }
    aligned = _core.align_blank(
        10 * unit, unit, 10.5 * unit, min_allowance=0.0, surface="quadric", k=None, spacing=None, init=None
    )
    results["_BlankAlignmentArrays"] = aligned
    results["_AlignmentStageArrays"] = aligned["stages"][0]
    # The comparison with CAD, the profiler exports and the sphere calibration.
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    tet_faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    results["_SignedArrays"] = _core.signed_distances(unit, tet, tet_faces)
    results["_FaceStatisticsArrays"] = _core.face_statistics(np.zeros(3), [0, 0, 1], count=2, lower=-1.0, upper=1.0)
    results["_MeshFitArrays"] = _core.fit_to_mesh(
        tet[:3] + 0.01,
        tet,
        tet_faces,
        1.0,
        init=None,
        dof="xyz",
        axis_point=None,
        axis_direction=None,
        max_iterations=5,
        relative_fitness=1e-6,
        relative_rmse=1e-6,
    )
    export = tmp_path / "k_height.csv"
    export.write_text("1234500\t1234600\t\n")
    results["_ProfileArrays"] = _core.read_profiles(export)
    sphere, truth = machscan.synth.sphere_scan(3, sweeps=2)
    results["_SphereCalibrationArrays"] = _core.calibrate_mount_sphere(
        sphere.frames,
        sphere.poses,
        pitch=sphere.profiler.pitch,
        center=None,
        valid_range=None,
        sentinel=None,
        c2_offset=sphere.c2_offset,
        radius=truth.radius,
        mount=sphere.mount,
        sphere_center=None,
    )
    assert set(results) == set(declared), "every TypedDict of the stub is checked here"
    for name, value in results.items():
        assert list(value) == declared[name], name


def _public_callables():
    modules = [
        machscan,
        machscan.io,
        machscan.cloud,
        machscan.kinematics,
        machscan.grooves,
        machscan.contours,
        machscan.inspection,
        machscan.scan,
        machscan.registration,
        machscan.mesh,
        machscan.matching,
        machscan.toolpath,
    ]
    seen = {}
    for m in modules:
        for name in getattr(m, "__all__", []):
            obj = getattr(m, name)
            if (callable(obj) and not inspect.isclass(obj)) or inspect.isbuiltin(obj):
                seen[f"{m.__name__}.{name}"] = obj
            elif inspect.isclass(obj):
                for meth_name, meth in vars(obj).items():
                    fn = getattr(obj, meth_name, None)
                    if not meth_name.startswith("_") and callable(fn) and not isinstance(meth, property):
                        seen[f"{m.__name__}.{name}.{meth_name}"] = fn
    return seen


def test_help_shows_every_default_no_ellipsis():
    for name, fn in _public_callables().items():
        try:
            sig = inspect.signature(fn)
        except (TypeError, ValueError):
            pytest.fail(f"{name}: no signature for help() to show")
        for p in sig.parameters.values():
            assert p.default is not Ellipsis, f"{name}({p.name}=...)"


def test_defaults_shown_are_the_defaults_used():
    assert inspect.signature(machscan.profile_to_points).parameters["sentinel"].default == _core.SENTINEL
    assert inspect.signature(machscan.scan_to_wcs).parameters["sentinel"].default == _core.SENTINEL
    assert inspect.signature(machscan.interpolate_poses).parameters["rotary"].default == (3, 4, 5)
    assert machscan.Profiler(readings=4, pitch=0.1).sentinel == _core.SENTINEL
    sig = inspect.signature(machscan.fit_grooves).parameters
    for k, v in machscan.grooves.DEFAULTS.items():
        if k in sig:
            assert sig[k].default == v, k
    c = machscan.FitCriteria()
    assert (c.max_iterations, c.step_tolerance, c.gradient_tolerance, c.cost_tolerance) == tuple(
        machscan.grooves.DEFAULTS[k] for k in ("max_iterations", "step_tolerance", "gradient_tolerance", "cost_tolerance")
    )


def test_the_gil_is_released_while_kernels_run():
    """Another Python thread runs while a kernel works: the counter advances."""
    rng = np.random.default_rng(3)
    big = rng.normal(0, 100, (3_000_000, 3))
    poly = np.column_stack([np.cos(np.linspace(0, 6, 400)), np.sin(np.linspace(0, 6, 400)), np.zeros(400)]) * 1000
    cents, others = rng.normal(0, 100, (1200, 3)), rng.normal(0, 100, (1200, 3))
    calls = {
        "voxel_downsample": lambda: machscan.voxel_downsample(big, 0.5),
        "crop_box": lambda: machscan.crop_box(big, (-50, -50, -50), (50, 50, 50)),
        "resample_polyline": lambda: machscan.resample_polyline(poly, 0.0005),
        "match_contours": lambda: machscan.match_contours(cents, others),
    }
    for name, call in calls.items():
        count = [0]
        done = threading.Event()

        def spin(count=count, done=done):
            while not done.is_set():
                count[0] += 1
                time.sleep(0)

        t = threading.Thread(target=spin)
        t.start()
        time.sleep(0.01)
        before = count[0]
        call()
        during = count[0] - before
        done.set()
        t.join()
        assert during > 10, f"{name}: the other thread ran {during} times"


def test_results_compare_and_hash_without_raising(tmp_path):
    # Results holding arrays compare by identity (eq=False): a generated __eq__ would compare the
    # arrays and raise "the truth value of an array is ambiguous". Two results computed alike are
    # equal in content but distinct objects: comparing them must answer, not raise.
    x = (np.arange(64) - 32) * 0.025
    makers = [
        lambda: machscan.fit_grooves(x, np.where(np.abs(x) < 0.25, -0.3, 0.0)[None, :]),
        lambda: machscan.io.read(DATA / "pcl-bunny-icp/bun0.pcd"),
        lambda: machscan.contour_error(P[:10], P[:12]),
        lambda: machscan.calibrate_mount(
            [[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1.0]], [[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1.0]]
        ),
        lambda: machscan.level_groove_frame(x, np.zeros(64)),
    ]
    for make in makers:
        a, b = make(), make()
        assert a == a and not (a != a)
        assert (a == b) is False and (a != b) is True, type(a).__name__
        assert isinstance(hash(a), int) and hash(a) != hash(b)
