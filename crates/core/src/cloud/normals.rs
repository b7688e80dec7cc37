//! Normals and curvature (SPEC F): PCA of each point's neighborhood, orientation, surface
//! variation, and principal curvatures from a local quadric fit.
use crate::error::{Error, Result};
use crate::spatial::{check_k, CloudNeighbors, Counting, Neighbor};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Which neighbors a point's estimate uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Neighborhood {
    /// The k nearest points, the point itself included (Open3D's `KDTreeSearchParamKNN`).
    Knn(usize),
    /// The nearest `max_nn` points strictly closer than `radius` (Open3D's
    /// `KDTreeSearchParamHybrid(radius, max_nn)`).
    Hybrid { radius: f64, max_nn: usize },
    /// The k nearest in the x–y projection, the point itself included. For height-field scans
    /// (z the cutting depth): the two sides of a vertical step are then neighbors, as they are
    /// on the part, while in 3D a step higher than the neighborhood separates them.
    KnnXy(usize),
}

impl Neighborhood {
    /// The neighbor count as every function checks it (`spatial::check_k`), and the radius.
    fn check(&self, n: usize) -> Result<()> {
        match *self {
            Neighborhood::Knn(k) | Neighborhood::KnnXy(k) => check_k("k", k, 3, n, Counting::WithSelf),
            Neighborhood::Hybrid { radius, max_nn } => {
                crate::error::check_positive("radius", radius, "mm")?;
                check_k("k", max_nn, 3, n, Counting::WithSelf)
            }
        }
    }

    /// `f(i, neighbors)` for every point, in point order; neighbor positions are 3D (the
    /// squared distances of `KnnXy` are in x–y).
    pub(crate) fn map<T: Send + Default>(
        &self,
        points: &[[f64; 3]],
        f: impl Fn(usize, &[Neighbor]) -> T + Sync,
    ) -> Result<Vec<T>> {
        Ok(match *self {
            Neighborhood::Knn(k) => CloudNeighbors::new(points)?.map_knn(k, None, f),
            Neighborhood::Hybrid { radius, max_nn } => CloudNeighbors::new(points)?.map_knn(max_nn, Some(radius), f),
            Neighborhood::KnnXy(k) => {
                let flat: Vec<[f64; 3]> = points.par_iter().map(|p| [p[0], p[1], 0.0]).collect();
                CloudNeighbors::new(&flat)?.map_knn(k, None, |i, nb| {
                    let lifted: Vec<Neighbor> = nb.iter().map(|n| Neighbor { point: points[n.index], ..*n }).collect();
                    f(i, &lifted)
                })
            }
        })
    }
}

/// Eigen-decomposition of the neighborhood covariance: eigenvalues ascending and their vectors.
/// `None` with fewer than 3 neighbors.
fn local_pca(nbrs: &[Neighbor]) -> Option<([f64; 3], [Vector3<f64>; 3])> {
    if nbrs.len() < 3 {
        return None;
    }
    // Centered sums: Open3D's raw-moment form loses digits far from the origin.
    let n = nbrs.len() as f64;
    let mut c = Vector3::zeros();
    for nb in nbrs {
        c += Vector3::from(nb.point);
    }
    c /= n;
    let mut m = Matrix3::zeros();
    for nb in nbrs {
        let d = Vector3::from(nb.point) - c;
        m += d * d.transpose();
    }
    m /= n;
    let eig = SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let vals = order.map(|k| eig.eigenvalues[k].max(0.0));
    let vecs = order.map(|k| eig.eigenvectors.column(k).into_owned());
    Some((vals, vecs))
}

/// Unoriented unit normals (smallest-eigenvalue eigenvector of the neighborhood covariance) and
/// the surface variation λ0/(λ0+λ1+λ2). A point with fewer than 3 neighbors gets (0, 0, 1)
/// (as Open3D) and variation 0, and is counted in the third return value.
pub fn estimate_normals(points: &[[f64; 3]], nbh: Neighborhood) -> Result<(Vec<[f64; 3]>, Vec<f64>, usize)> {
    crate::error::check_finite_points("points", points)?;
    nbh.check(points.len())?;
    if points.is_empty() {
        return Ok((Vec::new(), Vec::new(), 0));
    }
    let out: Vec<([f64; 3], f64, bool)> = nbh.map(points, |_, nbrs| match local_pca(nbrs) {
        Some((vals, vecs)) => {
            let s = vals[0] + vals[1] + vals[2];
            let n = vecs[0].normalize();
            ([n.x, n.y, n.z], if s > 0.0 { vals[0] / s } else { 0.0 }, false)
        }
        None => ([0.0, 0.0, 1.0], 0.0, true),
    })?;
    let degenerate = out.iter().filter(|o| o.2).count();
    Ok((out.iter().map(|o| o.0).collect(), out.iter().map(|o| o.1).collect(), degenerate))
}

/// Flip each normal to point towards `viewpoint` (n·(v − p) ≥ 0).
pub fn orient_towards(points: &[[f64; 3]], normals: &mut [[f64; 3]], viewpoint: [f64; 3]) {
    normals.par_iter_mut().zip(points).for_each(|(n, p)| {
        let d = (viewpoint[0] - p[0]) * n[0] + (viewpoint[1] - p[1]) * n[1] + (viewpoint[2] - p[2]) * n[2];
        if d < 0.0 {
            *n = [-n[0], -n[1], -n[2]];
        }
    });
}

/// Flip each normal to have a non-negative component along `direction`.
pub fn orient_along(normals: &mut [[f64; 3]], direction: [f64; 3]) {
    normals.par_iter_mut().for_each(|n| {
        if n[0] * direction[0] + n[1] * direction[1] + n[2] * direction[2] < 0.0 {
            *n = [-n[0], -n[1], -n[2]];
        }
    });
}

#[derive(PartialEq)]
struct Edge(f64, usize, usize);
impl Eq for Edge {}
impl PartialOrd for Edge {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Edge {
    // Min-heap on the weight, ties by index so the traversal is deterministic.
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then_with(|| o.2.cmp(&self.2)).then_with(|| o.1.cmp(&self.1))
    }
}

/// How normals are turned after estimation; at most one rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// The solver's sign.
    Unoriented,
    /// `n·(v − p) ≥ 0`: towards a viewpoint (the sensor).
    Towards([f64; 3]),
    /// `n·d ≥ 0`: along a direction.
    Along([f64; 3]),
    /// Propagated over the k-nearest graph (`orient_consistent`).
    Consistent,
}

impl Orientation {
    /// The rule from the three options of `estimate_normals`; more than one is an error.
    pub fn from_options(towards: Option<[f64; 3]>, along: Option<[f64; 3]>, consistent: bool) -> Result<Self> {
        match (towards, along, consistent) {
            (None, None, false) => Ok(Orientation::Unoriented),
            (Some(v), None, false) => Ok(Orientation::Towards(v)),
            (None, Some(d), false) => Ok(Orientation::Along(d)),
            (None, None, true) => Ok(Orientation::Consistent),
            _ => Err(Error::invalid("towards, along, consistent", "choose at most one orientation")),
        }
    }
}

/// Unit normals (`estimate_normals`) turned by `orientation`; consistent orientation propagates
/// over the same neighborhoods.
pub fn estimate_oriented_normals(
    points: &[[f64; 3]],
    nbh: Neighborhood,
    orientation: Orientation,
) -> Result<Vec<[f64; 3]>> {
    let (mut normals, _, _) = estimate_normals(points, nbh)?;
    match orientation {
        Orientation::Unoriented => {}
        Orientation::Towards(v) => {
            crate::error::check_finite("towards", &v, 3)?;
            orient_towards(points, &mut normals, v)
        }
        Orientation::Along(d) => {
            crate::error::check_finite("along", &d, 3)?;
            orient_along(&mut normals, d)
        }
        Orientation::Consistent => {
            let k = match nbh {
                Neighborhood::Knn(k) | Neighborhood::KnnXy(k) => k,
                Neighborhood::Hybrid { max_nn, .. } => max_nn,
            };
            // The same neighborhood as the normals: the point and its k − 1 others.
            orient_consistent(points, &mut normals, k - 1)?
        }
    }
    Ok(normals)
}

/// Consistent orientation by propagation (Hoppe et al. 1992): over the symmetric k-nearest graph
/// weighted by 1 − |n_i·n_j|, grow a minimum spanning tree (Prim) from the highest point, whose
/// normal is turned to +z, and flip each point to agree with its parent. Each connected part of
/// the graph starts again from its highest point.
pub fn orient_consistent(points: &[[f64; 3]], normals: &mut [[f64; 3]], k: usize) -> Result<()> {
    let n = points.len();
    check_k("k", k, 1, n, Counting::Others)?;
    if n == 0 {
        return Ok(());
    }
    // k + 1: the point itself is its own nearest neighbor (unless an exact duplicate with a
    // lower index comes first).
    let knn: Vec<Vec<usize>> = CloudNeighbors::new(points)?
        .map_knn(k + 1, None, |i, nb| nb.iter().map(|n| n.index).filter(|&j| j != i).take(k).collect());
    // Symmetric adjacency.
    let mut adj: Vec<Vec<usize>> = knn.clone();
    for (i, js) in knn.iter().enumerate() {
        for &j in js {
            adj[j].push(i);
        }
    }
    for a in adj.iter_mut() {
        a.sort_unstable();
        a.dedup();
    }
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut done = vec![false; n];
    let mut by_height: Vec<usize> = (0..n).collect();
    by_height.sort_by(|&a, &b| points[b][2].total_cmp(&points[a][2]).then(a.cmp(&b)));
    for &seed in &by_height {
        if done[seed] {
            continue;
        }
        if normals[seed][2] < 0.0 {
            normals[seed] = normals[seed].map(|v| -v);
        }
        done[seed] = true;
        let mut heap = BinaryHeap::new();
        for &j in &adj[seed] {
            heap.push(Edge(1.0 - dot(&normals[seed], &normals[j]).abs(), seed, j));
        }
        while let Some(Edge(_, parent, child)) = heap.pop() {
            if done[child] {
                continue;
            }
            if dot(&normals[parent], &normals[child]) < 0.0 {
                normals[child] = normals[child].map(|v| -v);
            }
            done[child] = true;
            for &j in &adj[child] {
                if !done[j] {
                    heap.push(Edge(1.0 - dot(&normals[child], &normals[j]).abs(), child, j));
                }
            }
        }
    }
    Ok(())
}

/// Principal curvatures `k1 >= k2` (1/mm) and their unit directions at one point.
pub type PrincipalCurvature = ([f64; 2], [[f64; 3]; 2]);

/// Principal curvatures (k1 ≥ k2, 1/mm) and principal directions from a quadric
/// `h = a u² + b uv + c v² + d u + e v + f` fitted to the neighbors in the local frame
/// (u, v tangent, h along the normal). The shape operator of the graph at the point is taken
/// at its foot (u, v) = (0, 0), corrected for the fitted slope (d, e). Signs follow the normal:
/// positive where the surface bends towards it (a sphere with inward normals has k1 = k2 = 1/R,
/// with outward normals −1/R); a point with fewer than 6 neighbors gets NaN. Without `normals`,
/// they are estimated over the same neighbourhood ([`estimate_normals`]).
pub fn principal_curvatures(
    points: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    nbh: Neighborhood,
) -> Result<Vec<PrincipalCurvature>> {
    crate::error::check_finite_points("points", points)?;
    nbh.check(points.len())?;
    let estimated;
    let normals = match normals {
        Some(n) => n,
        None => {
            estimated = estimate_normals(points, nbh)?.0;
            &estimated[..]
        }
    };
    crate::error::check_finite_points("normals", normals)?;
    if normals.len() != points.len() {
        return Err(Error::shape(
            "normals",
            format!("({}, 3): one per point", points.len()),
            format!("({}, 3)", normals.len()),
        ));
    }
    if points.is_empty() {
        return Ok(Vec::new());
    }
    nbh.map(points, |i, nb| {
        let (p, nrm) = (&points[i], &normals[i]);
        let nv = Vector3::from(*nrm).normalize();
        // A tangent basis.
        let helper = if nv.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let u = nv.cross(&helper).normalize();
        let v = nv.cross(&u);
        if nb.len() < 6 {
            return ([f64::NAN, f64::NAN], [[f64::NAN; 3]; 2]);
        }
        // Least squares on the 6 quadric coefficients.
        let mut ata = nalgebra::Matrix6::<f64>::zeros();
        let mut atb = nalgebra::Vector6::<f64>::zeros();
        for n in nb {
            let d = Vector3::from(n.point) - Vector3::from(*p);
            let (x, y, h) = (d.dot(&u), d.dot(&v), d.dot(&nv));
            let row = nalgebra::Vector6::new(x * x, x * y, y * y, x, y, 1.0);
            ata += row * row.transpose();
            atb += row * h;
        }
        let Some(sol) = ata.cholesky().map(|c| c.solve(&atb)) else {
            return ([f64::NAN, f64::NAN], [[f64::NAN; 3]; 2]);
        };
        let (a, b, c, d, e) = (sol[0], sol[1], sol[2], sol[3], sol[4]);
        // First and second fundamental forms of the graph h(x, y) at the origin.
        let (hx, hy, hxx, hxy, hyy) = (d, e, 2.0 * a, b, 2.0 * c);
        let w = (1.0 + hx * hx + hy * hy).sqrt();
        let first = nalgebra::Matrix2::new(1.0 + hx * hx, hx * hy, hx * hy, 1.0 + hy * hy);
        let second = nalgebra::Matrix2::new(hxx, hxy, hxy, hyy) / w;
        let Some(inv) = first.try_inverse() else {
            return ([f64::NAN, f64::NAN], [[f64::NAN; 3]; 2]);
        };
        let shape = inv * second;
        // The shape operator is symmetric in the metric; eigen-decompose it directly.
        let tr = shape.trace();
        let det = shape.determinant();
        let disc = (tr * tr / 4.0 - det).max(0.0).sqrt();
        let (k1, k2) = (tr / 2.0 + disc, tr / 2.0 - disc);
        let dir = |k: f64| -> [f64; 3] {
            // (shape − k I) t = 0 → t ⟂ first row.
            let (r0, r1) = (shape[(0, 0)] - k, shape[(0, 1)]);
            let (s0, s1) = (shape[(1, 0)], shape[(1, 1)] - k);
            let t = if r0.abs() + r1.abs() >= s0.abs() + s1.abs() { (-r1, r0) } else { (-s1, s0) };
            let t = if t.0 == 0.0 && t.1 == 0.0 { (1.0, 0.0) } else { t };
            let t3 = (u * t.0 + v * t.1 + nv * (hx * t.0 + hy * t.1)).normalize();
            [t3.x, t3.y, t3.z]
        };
        ([k1, k2], [dir(k1), dir(k2)])
    })
}
