//! Point insertion (SPEC S2; paper 002 §3.2, fig. 6): points of the surface become vertices of
//! its mesh, so that geodesic distances can start and end exactly there. A point at a vertex is
//! that vertex; on an edge, the edge's triangles are split in two each; inside a triangle, it
//! is split in three. Triangles are only ever split, never flipped: the surface and its area
//! stay exactly what they were.
use super::closest::{closest_on_triangle, TriangleBvh};
use crate::error::{check_finite_points, Error, Result};
use nalgebra::Vector3;

/// Where an inserted point landed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Landing {
    Vertex,
    Edge,
    Face,
}

/// The mesh with the points inserted.
#[derive(Debug, Clone)]
pub struct Inserted {
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// The vertex of each point.
    pub indices: Vec<u32>,
    pub landings: Vec<Landing>,
}

/// Inserts each point, in order, at its closest point of the mesh. A point within `tolerance`
/// (mm) of a vertex is that vertex; within `tolerance` of an edge it splits the edge.
pub fn insert_points(
    vertices: &[[f64; 3]],
    faces: &[[u32; 3]],
    points: &[[f64; 3]],
    tolerance: f64,
) -> Result<Inserted> {
    check_finite_points("points", points)?;
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid("tolerance", format!("must be ≥ 0 mm, got {tolerance}")));
    }
    let bvh = TriangleBvh::new(vertices, faces)?;
    let mut out = Inserted { vertices: vertices.to_vec(), faces: faces.to_vec(), indices: vec![], landings: vec![] };
    // The triangles each original triangle has been split into (its descendants); a point is
    // located on the original mesh, then among that triangle's descendants, which tile it.
    let mut pieces: Vec<Vec<usize>> = (0..faces.len()).map(|t| vec![t]).collect();
    let mut origin: Vec<usize> = (0..faces.len()).collect();
    for p in points {
        let first = bvh.closest(p).triangle;
        let q = Vector3::from(*p);
        let corner = |out: &Inserted, f: usize, k: usize| Vector3::from(out.vertices[out.faces[f][k] as usize]);
        // The closest descendant (ties to the lowest index).
        let (mut best, mut best_d2, mut at) = (usize::MAX, f64::INFINITY, q);
        for &f in &pieces[first] {
            let (x, _) = closest_on_triangle(&q, &corner(&out, f, 0), &corner(&out, f, 1), &corner(&out, f, 2));
            let d2 = (x - q).norm_squared();
            if d2 < best_d2 || (d2 == best_d2 && f < best) {
                (best, best_d2, at) = (f, d2, x);
            }
        }
        let f = out.faces[best];
        let c = [0, 1, 2].map(|k| corner(&out, best, k));
        // The nearest corner, and the nearest edge (k, k+1), from the landing point.
        let (kv, dv) =
            (0..3).map(|k| (k, (c[k] - at).norm())).fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        if dv <= tolerance {
            out.indices.push(f[kv]);
            out.landings.push(Landing::Vertex);
            continue;
        }
        let edge_distance = |k: usize| {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let t = ((at - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
            (a + t * (b - a) - at).norm()
        };
        let (ke, de) =
            (0..3).map(|k| (k, edge_distance(k))).fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        let v = out.vertices.len() as u32;
        out.vertices.push(at.into());
        out.indices.push(v);
        if de <= tolerance {
            // Split every triangle on the edge (a, b): (a, b, x) → (a, v, x) and (v, b, x).
            let (a, b) = (f[ke], f[(ke + 1) % 3]);
            let on_edge = edge_faces(&out.faces, a, b);
            for t in on_edge {
                let g = out.faces[t];
                let k = (0..3).find(|&k| (g[k] == a && g[(k + 1) % 3] == b) || (g[k] == b && g[(k + 1) % 3] == a));
                let Some(k) = k else { continue };
                let (s, e, x) = (g[k], g[(k + 1) % 3], g[(k + 2) % 3]);
                out.faces[t] = [s, v, x];
                out.faces.push([v, e, x]);
                let o = origin[t];
                origin.push(o);
                pieces[o].push(out.faces.len() - 1);
            }
            out.landings.push(Landing::Edge);
        } else {
            // Split the triangle in three round the new vertex.
            let [a, b, cc] = f;
            out.faces[best] = [a, b, v];
            out.faces.push([b, cc, v]);
            out.faces.push([cc, a, v]);
            let o = origin[best];
            origin.extend([o, o]);
            let n = out.faces.len();
            pieces[o].extend([n - 2, n - 1]);
            out.landings.push(Landing::Face);
        }
    }
    Ok(out)
}

/// The triangles that hold the edge (a, b): one on the boundary, two inside. One pass over
/// the faces per edge insertion (a few per call) keeps the bookkeeping simple.
fn edge_faces(faces: &[[u32; 3]], a: u32, b: u32) -> Vec<usize> {
    (0..faces.len()).filter(|&t| faces[t].contains(&a) && faces[t].contains(&b)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(v: &[[f64; 3]], f: &[[u32; 3]]) -> f64 {
        f.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vector3::from(v[i as usize]));
                (b - a).cross(&(c - a)).norm() / 2.0
            })
            .sum()
    }

    #[test]
    fn vertex_edge_and_face_landings_keep_the_surface() {
        // Two triangles of a unit square, sharing the diagonal (0, 2).
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let f = [[0, 1, 2], [0, 2, 3]];
        let pts = [[1.0, 1.0, 0.3], [0.5, 0.5, 0.0], [0.7, 0.2, 0.0], [0.5, 0.0, 0.0]];
        let r = insert_points(&v, &f, &pts, 1e-9).unwrap();
        assert_eq!(r.landings, [Landing::Vertex, Landing::Edge, Landing::Face, Landing::Edge]);
        assert_eq!(r.indices[0], 2);
        assert_eq!(r.vertices.len(), 7);
        // Diagonal split: 4 triangles; face split: +2; boundary edge split: +1.
        assert_eq!(r.faces.len(), 2 + 2 + 2 + 1);
        assert!((area(&r.vertices, &r.faces) - 1.0).abs() < 1e-15);
        for (i, &k) in r.indices.iter().enumerate().skip(1) {
            assert!((Vector3::from(r.vertices[k as usize]) - Vector3::from(pts[i])).norm() < 1e-15);
            assert!(r.faces.iter().filter(|t| t.contains(&k)).count() >= 2);
        }
        // Every triangle keeps the orientation of the mesh (+z).
        for t in &r.faces {
            let [a, b, c] = t.map(|i| Vector3::from(r.vertices[i as usize]));
            assert!((b - a).cross(&(c - a))[2] > 0.0);
        }
    }

    #[test]
    fn bad_arguments_are_refused_by_name() {
        let v = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(insert_points(&v, &[[0, 1, 2]], &[[0.2; 3]], -1.0).unwrap_err().to_string().contains("tolerance"));
        assert!(insert_points(&v, &[[0, 1, 5]], &[[0.2; 3]], 0.0).unwrap_err().to_string().contains("faces"));
    }
}
