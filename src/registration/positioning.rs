//! Positioning errors (SPEC R5; paper 003 eq 11–14): how far each measured point lies from the
//! model, per axis. Against a model given as points alone the reference is the closest model
//! point; with normals it is the closest point of the model surface, the tangent plane at the
//! closest model point (the sampling of the model then does not count as error).
use crate::error::{check_finite_points, Error, Result};
use crate::spatial::PointIndex;
use nalgebra::Vector3;
use rayon::prelude::*;

/// `e = p − q` for each measured point p (`e_x, e_y, e_z`; `e_total = |e|` is the caller's):
/// q the closest model point, or with `normals` the foot of p on the tangent plane there, so
/// that `e = ((p − q)·n) n`.
pub fn positioning_errors(
    measured: &[[f64; 3]],
    model: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
) -> Result<Vec<[f64; 3]>> {
    check_finite_points("measured", measured)?;
    check_finite_points("model_points", model)?;
    if model.is_empty() {
        return Err(Error::invalid("model_points", "must hold at least one point"));
    }
    if let Some(n) = normals {
        super::check_normals("model_normals", n, model.len())?;
    }
    let index = PointIndex::new(model)?;
    Ok(measured
        .par_iter()
        .map(|p| {
            let (j, _) = index.nearest_squared(p);
            let d = Vector3::from(*p) - Vector3::from(model[j]);
            match normals {
                Some(n) => {
                    let n = Vector3::from(n[j]).normalize();
                    (d.dot(&n) * n).into()
                }
                None => d.into(),
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_against_points_and_against_the_surface() {
        // A plane z = 0 sampled every 1 mm; measured points 10 µm above it, anywhere in x, y.
        let model: Vec<[f64; 3]> = (0..400).map(|i| [(i % 20) as f64, (i / 20) as f64, 0.0]).collect();
        let normals = vec![[0.0, 0.0, 2.0]; model.len()];
        let measured = [[3.3, 7.6, 0.01], [10.45, 2.2, 0.01]];
        let surface = positioning_errors(&measured, &model, Some(&normals)).unwrap();
        assert!(surface.iter().all(|e| e[0] == 0.0 && e[1] == 0.0 && (e[2] - 0.01).abs() < 1e-15));
        let points = positioning_errors(&measured, &model, None).unwrap();
        assert!((points[0][0] - 0.3).abs() < 1e-12 && (points[0][1] + 0.4).abs() < 1e-12);
        assert!(positioning_errors(&measured, &model, Some(&normals[..3]))
            .unwrap_err()
            .to_string()
            .contains("model_normals"));
    }
}
