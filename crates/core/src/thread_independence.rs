//! Every rayon kernel gives bit-identical results on 1, 2 and 4 threads (DESIGN: fixed-order
//! reductions, no concurrent pushes). One rstest template, `threads`, runs each test case with
//! the kernel on a pool of that many threads and compares with the result on one thread.
use crate::cloud::{self, NeighborSpace, Neighborhood, OctreeOptions, Orientation};
use crate::groove::{fit_frames, GrooveOptions, TanhTemplate};
use crate::kinematics::{frames_to_points, KinematicChain, Profiler};
use crate::testing::lcg;
use rstest::rstest;
use rstest_reuse::{apply, template};

#[template]
#[rstest]
#[case(1)]
#[case(2)]
#[case(4)]
fn threads(#[case] threads: usize) {}

/// `f()` on a pool of `threads` threads, and on one thread.
fn on_threads_and_one<T: Send>(threads: usize, f: impl Fn() -> T + Send + Sync) -> (T, T) {
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("a thread pool");
    (pool(threads).install(&f), pool(1).install(&f))
}

/// A wavy scanned surface with some outliers: enough points that every kernel splits its work.
fn surface(n: usize) -> Vec<[f64; 3]> {
    let mut s = 7u64;
    (0..n)
        .map(|i| {
            let (x, y) = (lcg(&mut s) * 60.0, lcg(&mut s) * 40.0);
            let z = 0.5 * (0.2 * x).sin() * (0.15 * y).cos() + 0.01 * lcg(&mut s);
            if i % 997 == 0 {
                [x, y, z + 5.0 * lcg(&mut s)]
            } else {
                [x, y, z]
            }
        })
        .collect()
}

fn bits(v: &[[f64; 3]]) -> Vec<[u64; 3]> {
    v.iter().map(|p| p.map(f64::to_bits)).collect()
}

#[apply(threads)]
fn voxel_grid(#[case] threads: usize) {
    let pts = surface(12_000);
    let (a, b) = on_threads_and_one(threads, || cloud::voxel_downsample(&pts, 0.7).unwrap());
    assert_eq!(bits(&a.centroids), bits(&b.centroids));
    assert_eq!(a.voxel_of_point, b.voxel_of_point);
}

#[apply(threads)]
fn outlier_filters_and_duplicates(#[case] threads: usize) {
    let pts = surface(10_000);
    let (a, b) = on_threads_and_one(threads, || {
        (
            cloud::remove_statistical_outliers(&pts, 16, 2.0).unwrap(),
            cloud::remove_radius_outliers(&pts, 0.6, 4).unwrap(),
            cloud::remove_duplicates(&pts, 0.05).unwrap(),
            cloud::crop_box(&pts, [10.0, 5.0, -1.0], [40.0, 30.0, 1.0]).unwrap(),
        )
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn normals_orientation_and_curvature(#[case] threads: usize) {
    let pts = surface(8_000);
    let (a, b) = on_threads_and_one(threads, || {
        let consistent =
            cloud::estimate_oriented_normals(&pts, Neighborhood::Knn(12), Orientation::Consistent).unwrap();
        let hybrid = cloud::estimate_oriented_normals(
            &pts,
            Neighborhood::Hybrid { radius: 1.0, max_nn: 20 },
            Orientation::Unoriented,
        )
        .unwrap();
        let curv = cloud::principal_curvatures(&pts, Some(&consistent), Neighborhood::Knn(20)).unwrap();
        (bits(&consistent), bits(&hybrid), curv.iter().map(|c| c.0.map(f64::to_bits)).collect::<Vec<_>>())
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn octree_simplification(#[case] threads: usize) {
    let pts = surface(8_000);
    let mut o = OctreeOptions::new(2.0);
    o.neighbors = NeighborSpace::Xy;
    o.refine = 2;
    let (a, b) = on_threads_and_one(threads, || {
        (
            cloud::octree_simplify(&pts, None, &OctreeOptions::new(1.5)).unwrap(),
            cloud::octree_simplify(&pts, None, &o).unwrap(),
        )
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn clustering_both_forms(#[case] threads: usize) {
    let pts = surface(12_000);
    let (a, b) = on_threads_and_one(threads, || {
        (
            crate::spatial::euclidean_clusters(&pts, 0.3, None).unwrap(),
            crate::spatial::euclidean_clusters(&pts, 0.5, Some(5)).unwrap(),
        )
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn neighbor_queries(#[case] threads: usize) {
    let pts = surface(10_000);
    let queries: Vec<[f64; 3]> = pts.iter().step_by(7).map(|p| [p[0] + 0.01, p[1] - 0.02, p[2]]).collect();
    let (a, b) = on_threads_and_one(threads, || {
        let (idx, dist) = crate::spatial::knn_graph(&pts, 9, Some(0.8)).unwrap();
        let (ni, nd) = crate::spatial::nearest_neighbors(&pts, &queries).unwrap();
        (
            idx,
            dist.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
            ni,
            nd.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
        )
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn contour_error(#[case] threads: usize) {
    let mut s = 3u64;
    let p: Vec<[f64; 3]> =
        (0..5000).map(|i| (i as f64 * 0.00126).sin_cos()).map(|(y, x)| [30.0 * x, 30.0 * y, 0.0]).collect();
    let q: Vec<[f64; 3]> = p.iter().map(|v| [v[0] + 0.1 * lcg(&mut s), v[1] + 0.1 * lcg(&mut s), 0.02]).collect();
    let (a, b) = on_threads_and_one(threads, || crate::contour::contour_error(&p, &q, 1.0, 1.0).unwrap());
    assert_eq!(a, b);
}

#[apply(threads)]
fn chains_and_scans(#[case] threads: usize) {
    let chain = KinematicChain::ac_head([10.0, 0.0, 120.0], [0.01, 0.02, -0.03, 40.0, 1.0, -90.0]).unwrap();
    let (f, n) = (700, 301);
    let mut s = 5u64;
    let frames: Vec<f64> =
        (0..f * n).map(|i| if i % 37 == 0 { f64::NAN } else { (i % n) as f64 * 0.003 + lcg(&mut s) }).collect();
    let poses: Vec<f64> = (0..f * 6).map(|_| lcg(&mut s) * 2.0 - 1.0).collect();
    let prof = Profiler::new(0.025, n, None, Some((-5.0, 5.0)), Some(-99999.0)).unwrap();
    let pts: Vec<[f64; 3]> = surface(5_000);
    let (a, b) = on_threads_and_one(threads, || {
        let scan = frames_to_points(&chain, &frames, n, &poses, &prof).unwrap();
        let transforms = chain.transforms(&poses).unwrap();
        let turned = crate::kinematics::ac_table_rotate(&pts, Some(&pts), 0.3, -1.1, [1.0, 2.0, 3.0]).unwrap();
        (
            scan.points.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            scan.frame_index,
            transforms.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            bits(&turned.0),
        )
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn groove_fits(#[case] threads: usize) {
    let mut s = 9u64;
    let x: Vec<f64> = (0..200).map(|i| (i as f64 - 100.0) * 0.025).collect();
    let mut z = Vec::new();
    for _ in 0..400 {
        let t = TanhTemplate { x0: 0.2 * lcg(&mut s) - 0.1, z0: 0.0, depth: 0.31, width: 0.48, alpha: 20.0 };
        z.extend(x.iter().map(|&xi| t.value(xi) + 0.008 * (lcg(&mut s) - 0.5)));
    }
    // Both methods; compared bit for bit (NaN fields included).
    let key = |f: &crate::groove::GrooveFit| {
        [f.x0, f.z0, f.width, f.depth, f.alpha, f.rms, f.se_width, f.tilt, f.area, f.se_area, f.step, f.se_step]
            .map(f64::to_bits)
            .to_vec()
    };
    for template in [crate::groove::TemplateKind::Auto, crate::groove::TemplateKind::Tanh] {
        let o = GrooveOptions { template, ..GrooveOptions::default() };
        let (a, b) = on_threads_and_one(threads, || fit_frames(&x, &z, &o).unwrap().fits);
        assert!(a.iter().zip(&b).all(|(p, q)| key(p) == key(q) && p.status == q.status && p.model == q.model));
    }
}

#[apply(threads)]
fn readers(#[case] threads: usize) {
    let pts: Vec<f64> = surface(8_000).into_iter().flatten().collect();
    let dir = std::env::temp_dir();
    let files: Vec<std::path::PathBuf> = ["ply", "pcd", "xyz"]
        .iter()
        .map(|e| dir.join(format!("machscan-threads-{}-{threads}.{e}", std::process::id())))
        .collect();
    for (path, binary) in files.iter().zip([false, true, false]) {
        let data = crate::io::CloudRef { points: &pts, ..Default::default() };
        crate::io::write_file(path, &data, crate::io::WriteOptions { binary: Some(binary), ..Default::default() })
            .unwrap();
    }
    let (a, b) = on_threads_and_one(threads, || {
        files.iter().map(|p| crate::io::read_file(p, crate::io::TextColumns::default()).unwrap()).collect::<Vec<_>>()
    });
    for p in &files {
        std::fs::remove_file(p).ok();
    }
    assert_eq!(a, b);
}

#[apply(threads)]
fn icp_point_to_point_and_point_to_plane(#[case] threads: usize) {
    use crate::registration::{icp, IcpMethod, IcpOptions};
    let target = surface(8_000);
    let (normals, _, _) = cloud::estimate_normals(&target, Neighborhood::Knn(12)).unwrap();
    let mut shift = nalgebra::Matrix4::identity();
    shift[(0, 3)] = 0.3;
    shift[(1, 3)] = -0.2;
    let source: Vec<[f64; 3]> = target.iter().map(|&p| crate::geom::transform_point(&shift, p)).collect();
    for method in [IcpMethod::PointToPoint, IcpMethod::PointToPlane] {
        let o = IcpOptions { method, max_iterations: 10, ..IcpOptions::new(1.0) };
        let run = || icp(&source, &target, Some(&normals), &nalgebra::Matrix4::identity(), &o).unwrap();
        let (a, b) = on_threads_and_one(threads, run);
        assert_eq!(a.transformation.map(f64::to_bits), b.transformation.map(f64::to_bits), "{method:?}");
        assert_eq!(
            (a.fitness.to_bits(), a.rmse.to_bits(), a.iterations),
            (b.fitness.to_bits(), b.rmse.to_bits(), b.iterations)
        );
    }
}

/// Model points, their normals, and a blank 0.2–0.4 mm over them.
type ModelAndBlank = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A blank 0.2–0.4 mm over the wavy surface: model points with their normals, and the blank.
fn model_and_blank() -> ModelAndBlank {
    let wave = |x: f64, y: f64| 0.5 * (0.2 * x).sin() * (0.15 * y).cos();
    let normal = |x: f64, y: f64| {
        let (gx, gy) = (0.1 * (0.2 * x).cos() * (0.15 * y).cos(), -0.075 * (0.2 * x).sin() * (0.15 * y).sin());
        let l = (gx * gx + gy * gy + 1.0).sqrt();
        [-gx / l, -gy / l, 1.0 / l]
    };
    let (mut model, mut normals) = (Vec::new(), Vec::new());
    for i in 0..12 {
        for j in 0..8 {
            let (x, y) = (10.0 + 2.0 * i as f64, 8.0 + 2.0 * j as f64);
            model.push([x, y, wave(x, y)]);
            normals.push(normal(x, y));
        }
    }
    let mut s = 3u64;
    // A jittered grid every 0.5 mm (a scan's points are spread evenly, not at random).
    let blank = (0..64 * 48)
        .map(|k| {
            let (x, y) =
                (5.0 + 0.5 * ((k % 64) as f64 + 0.6 * lcg(&mut s)), 3.0 + 0.5 * ((k / 64) as f64 + 0.6 * lcg(&mut s)));
            let n = normal(x, y);
            let d = 0.3 + 0.1 * (0.1 * x).sin();
            [x + d * n[0], y + d * n[1], wave(x, y) + d * n[2]]
        })
        .collect();
    (model, normals, blank)
}

#[apply(threads)]
fn allowance_envelope_and_alignment(#[case] threads: usize) {
    use crate::registration::{align_blank, allowance, coarse_align, envelope_fit, BlankOptions, BlankSurface};
    let (model, normals, blank) = model_and_blank();
    let plane = BlankOptions { surface: BlankSurface::Plane, k: None, spacing: None };
    let identity = nalgebra::Matrix4::identity();
    let (a, b) = on_threads_and_one(threads, || {
        let quadric = allowance(&model, &normals, &blank, &BlankOptions::default()).unwrap();
        let flat = allowance(&model, &normals, &blank, &plane).unwrap();
        let fit = envelope_fit(&model, &normals, &blank, 0.1, &BlankOptions::default(), &identity).unwrap();
        let aligned = align_blank(&model, &normals, &blank, 0.1, &BlankOptions::default(), &identity).unwrap();
        let coarse = coarse_align(&blank, &model).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (
            bits(&quadric),
            bits(&flat),
            bits(fit.transformation.as_slice()),
            bits(&fit.allowance),
            bits(aligned.fit.transformation.as_slice()),
            bits(coarse.as_slice()),
        )
    });
    assert!(a.0.iter().all(|x| f64::from_bits(*x).is_finite()), "the blank covers every model point");
    assert_eq!(a, b);
}

#[apply(threads)]
fn probe_points_and_positioning(#[case] threads: usize) {
    use crate::registration::{cloud_locating_points, positioning_errors, probe_fit, ProbePattern};
    let (model, normals, _) = model_and_blank();
    let measured: Vec<[f64; 3]> = model.iter().map(|p| [p[0] + 0.01, p[1] - 0.02, p[2] + 0.03]).collect();
    let (a, b) = on_threads_and_one(threads, || {
        let chosen = cloud_locating_points(&model, Some(&normals), 20, 0.5, 12, 7, ProbePattern::Optimal).unwrap();
        let random = cloud_locating_points(&model, None, 20, 0.5, 12, 7, ProbePattern::Random).unwrap();
        let errors = positioning_errors(&measured, &model, Some(&normals)).unwrap();
        let fit = probe_fit(&measured, &model, &normals, 0.0, &nalgebra::Matrix4::identity()).unwrap();
        (chosen, random, bits(&errors), fit.transformation.as_slice().iter().map(|x| x.to_bits()).collect::<Vec<_>>())
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn meshes_closest_points_and_geodesics(#[case] threads: usize) {
    use crate::mesh::{closest_points, delaunay_xy, geodesic_distances, GeodesicMethod};
    let pts: Vec<[f64; 3]> = surface(6_000).into_iter().filter(|p| p[2] < 1.0).collect();
    let (a, b) = on_threads_and_one(threads, || {
        let faces = delaunay_xy(&pts, None).unwrap();
        let queries: Vec<[f64; 3]> = pts.iter().step_by(7).map(|p| [p[0] + 0.1, p[1] - 0.1, p[2] + 0.3]).collect();
        let closest: Vec<[u64; 3]> =
            closest_points(&pts, &faces, &queries).unwrap().iter().map(|c| c.point.map(f64::to_bits)).collect();
        let rows = |method| {
            let d = geodesic_distances(&pts, &faces, &[0, 1000, 3000], method).unwrap();
            d.concat().iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        };
        let one = geodesic_distances(&pts, &faces, &[2000], GeodesicMethod::Exact).unwrap();
        let (fmm, exact, heat) = (rows(GeodesicMethod::Fmm), rows(GeodesicMethod::Exact), rows(GeodesicMethod::Heat));
        (faces, closest, fmm, exact, heat, one)
    });
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
    assert_eq!((&a.2, &a.3, &a.4), (&b.2, &b.3, &b.4));
    assert!(a.5[0].iter().zip(&b.5[0]).all(|(x, y)| x.to_bits() == y.to_bits()), "one source, two parts");
}

#[apply(threads)]
fn signed_distances_and_the_fit_to_a_mesh(#[case] threads: usize) {
    use crate::mesh::{delaunay_xy, face_statistics, signed_distances};
    use crate::registration::{fit_to_mesh, Dof, MeshFitOptions};
    let pts: Vec<[f64; 3]> = surface(6_000).into_iter().filter(|p| p[2] < 1.0).collect();
    let (a, b) = on_threads_and_one(threads, || {
        let faces = delaunay_xy(&pts, None).unwrap();
        let scan: Vec<[f64; 3]> = pts.iter().step_by(3).map(|p| [p[0] + 0.05, p[1] - 0.04, p[2] + 0.02]).collect();
        let signed = signed_distances(&pts, &faces, &scan).unwrap();
        let d: Vec<f64> = signed.iter().map(|s| s.distance).collect();
        let group: Vec<u32> = signed.iter().map(|s| (s.closest.triangle % 5) as u32).collect();
        let stats = face_statistics(&d, &group, 5, -0.01, 0.01).unwrap();
        let o = MeshFitOptions { dof: Dof::parse("xyzc").unwrap(), ..MeshFitOptions::new(1.0) };
        let fit = fit_to_mesh(&scan, &pts, &faces, &nalgebra::Matrix4::identity(), &o).unwrap();
        let pose: Vec<u64> = fit.icp.transformation.as_slice().iter().map(|x| x.to_bits()).collect();
        (d.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), format!("{stats:?}"), pose, fit.icp.iterations)
    });
    assert_eq!(a, b);
}

#[apply(threads)]
fn grinding_paths_and_the_simulated_pass(#[case] threads: usize) {
    use crate::toolpath::grinding::{grinding_paths, simulate_removal, GrindingOptions, Stock};
    let (model, normals, _) = model_and_blank();
    let allowance: Vec<f64> = model.iter().map(|p| 0.2 + 0.002 * p[0] + 0.001 * p[1]).collect();
    let options = GrindingOptions {
        tool_radius: 8.0,
        scallop_height: 0.01,
        section_normal: [0.0, 1.0, 0.0],
        thickness: None,
        spacing: None,
        tolerance: None,
        fit_radius: None,
        removal: None,
        feed_step: None,
    };
    let (a, b) = on_threads_and_one(threads, || {
        let g = grinding_paths(&model, &normals, &allowance, &options).unwrap();
        let depths = vec![0.1; g.points.len()];
        let blank = Stock { points: &model, normals: &normals, allowance: &allowance };
        let path = Stock { points: &g.points, normals: &g.normals, allowance: &g.allowance };
        let (left, nearest) = simulate_removal(blank, path, &g.row, &depths, 8.0).unwrap();
        (bits(&g.points), g.row, left.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), nearest)
    });
    assert!(a.0.len() > 20 && a.2.len() == 96, "a path over the patch: {} points", a.0.len());
    assert_eq!(a, b);
}

#[apply(threads)]
fn toolpath_compensation(#[case] threads: usize) {
    use crate::mesh::ScanSurface;
    use crate::toolpath::{compensate_toolpath, CompensateOptions, Interpolation, Normals};
    let scan: Vec<[f64; 3]> = surface(5_000).into_iter().filter(|p| p[2] < 1.0).collect();
    // Matching points on a grid, the actual ones moved a little (a bend), and tool points between.
    let theoretical: Vec<[f64; 3]> =
        (0..36).map(|k| [8.0 + 9.0 * (k % 6) as f64, 5.0 + 6.0 * (k / 6) as f64, 0.0]).collect();
    let actual: Vec<[f64; 3]> = theoretical.iter().map(|p| [p[0] + 0.002 * p[1], p[1] - 0.001 * p[0], 0.0]).collect();
    let tools: Vec<[f64; 3]> = (0..400).map(|k| [10.0 + 0.11 * k as f64, 8.0 + 0.05 * k as f64, -0.5]).collect();
    let (a, b) = on_threads_and_one(threads, || {
        let mut out = Vec::new();
        for (interpolation, normals) in
            [(Interpolation::Cubic, Normals::Smooth), (Interpolation::Linear, Normals::Triangle)]
        {
            let o = CompensateOptions { interpolation, normals, radius: None, max_edge: None };
            let c =
                compensate_toolpath(&tools, None, &theoretical, &actual, ScanSurface { points: &scan, faces: None }, o)
                    .unwrap();
            out.push((bits(&c.points), bits(&c.axes), c.inside, c.on_scan));
        }
        out
    });
    assert_eq!(a, b);
}
