//! Locating a physical point in a hexahedral mesh and interpolating nodal fields there.
//!
//! Used by the wheel passage to evaluate mode shapes at the (moving) contact point: find the
//! element that contains the point (bounding-box filter, then Newton inversion of the
//! isoparametric map, [`hex8::natural_coordinates`]), then interpolate the nodal
//! displacements with the trilinear shape functions (the incompatible modes are internal and
//! not part of the nodal field).

use super::hex8;
use super::FeError;
use crate::mesh::Mesh;

/// A point located in an element: element index and natural coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Location {
    /// Element index in the mesh.
    pub element: usize,
    /// Natural coordinates `[ξ, η, ζ]`, each in `[−1 − tol, 1 + tol]`.
    pub xi: [f64; 3],
}

/// Finds an element containing the point `p` (m), with natural-coordinate tolerance `tol`
/// (e.g. 1e-9; a point on a shared face is reported in the first element found). Only the
/// elements listed in `candidates` are searched, or all when `None`. Returns `Ok(None)` when
/// no element contains the point.
pub fn locate_point(
    mesh: &Mesh,
    p: [f64; 3],
    tol: f64,
    candidates: Option<&[usize]>,
) -> Result<Option<Location>, FeError> {
    let all: Vec<usize>;
    let list = match candidates {
        Some(c) => c,
        None => {
            all = (0..mesh.elements.len()).collect();
            &all
        }
    };
    for &e in list {
        let el = mesh
            .elements
            .get(e)
            .ok_or_else(|| FeError::IndexOutOfRange {
                what: "candidate element".into(),
                index: e,
                len: mesh.elements.len(),
            })?;
        let mut c = [[0.0; 3]; 8];
        for (a, &n) in el.nodes.iter().enumerate() {
            c[a] = *mesh.nodes.get(n).ok_or_else(|| FeError::IndexOutOfRange {
                what: format!("element {e} node"),
                index: n,
                len: mesh.nodes.len(),
            })?;
        }
        // Bounding box with a relative margin.
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for x in &c {
            for d in 0..3 {
                lo[d] = lo[d].min(x[d]);
                hi[d] = hi[d].max(x[d]);
            }
        }
        let inside_box = (0..3).all(|d| {
            let m = (hi[d] - lo[d]) * (tol + 1e-12);
            p[d] >= lo[d] - m && p[d] <= hi[d] + m
        });
        if !inside_box {
            continue;
        }
        match hex8::natural_coordinates(&c, p) {
            Ok(xi) if hex8::is_inside(xi, tol) => return Ok(Some(Location { element: e, xi })),
            Ok(_) | Err(FeError::NewtonNotConverged { .. }) => continue,
            Err(err) => {
                return Err(match err {
                    FeError::NonPositiveJacobian { det_j, xi, .. } => {
                        FeError::NonPositiveJacobian {
                            element: Some(e),
                            det_j,
                            xi,
                        }
                    }
                    other => other,
                })
            }
        }
    }
    Ok(None)
}

/// Interpolates a full nodal vector field `u_full` (length `3 n_nodes`, e.g. an expanded
/// mode shape, m) at a located point.
pub fn interpolate_at(mesh: &Mesh, loc: &Location, u_full: &[f64]) -> Result<[f64; 3], FeError> {
    if u_full.len() != 3 * mesh.nodes.len() {
        return Err(FeError::DimensionMismatch {
            what: "nodal field".into(),
            expected: 3 * mesh.nodes.len(),
            got: u_full.len(),
        });
    }
    let el = mesh
        .elements
        .get(loc.element)
        .ok_or_else(|| FeError::IndexOutOfRange {
            what: "located element".into(),
            index: loc.element,
            len: mesh.elements.len(),
        })?;
    let n = hex8::shape_functions(loc.xi);
    let vals: [[f64; 3]; 8] =
        std::array::from_fn(|a| [0, 1, 2].map(|d| u_full[3 * el.nodes[a] + d]));
    Ok(hex8::interpolate_vector(&n, &vals))
}

#[cfg(test)]
mod tests {
    use super::{interpolate_at, locate_point};
    use crate::fe::block::block_mesh;
    use crate::mesh::Part;

    #[test]
    fn linear_field_is_interpolated_exactly_at_located_points() {
        // Trilinear interpolation reproduces a linear field exactly (closed form).
        let mut mesh = block_mesh([4, 3, 2], [0.4, 0.3, 0.2], 0, Part::Rail);
        for (i, p) in mesh.nodes.iter_mut().enumerate() {
            p[2] += 0.004 * ((i * 7919) % 13) as f64 / 13.0; // mild distortion
        }
        let f = |p: [f64; 3]| [1.0 + 2.0 * p[0] - p[1], 0.5 * p[2], p[0] + p[1] + p[2]];
        let u: Vec<f64> = mesh.nodes.iter().flat_map(|&p| f(p)).collect();
        for p in [[0.13, 0.21, 0.07], [0.351, 0.02, 0.15], [0.2, 0.15, 0.1]] {
            let loc = locate_point(&mesh, p, 1e-9, None).unwrap().expect("inside");
            let v = interpolate_at(&mesh, &loc, &u).unwrap();
            let e = f(p);
            for d in 0..3 {
                assert!((v[d] - e[d]).abs() < 1e-12, "{v:?} vs {e:?}");
            }
        }
        assert!(locate_point(&mesh, [1.0, 0.0, 0.0], 1e-9, None)
            .unwrap()
            .is_none());
    }
}
