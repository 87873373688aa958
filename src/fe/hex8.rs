//! The 8-node hexahedron with incompatible modes (Wilson–Taylor), its mass, and
//! isoparametric interpolation.
//!
//! # Model
//! Linear elasticity, small strains, isotropic material. The displacement is the trilinear
//! isoparametric field `u = Σ_a N_a(ξ) u_a` plus Wilson's nine *incompatible modes*
//! `Σ_k P_k(ξ) α_k`, `P_1 = 1 − ξ²`, `P_2 = 1 − η²`, `P_3 = 1 − ζ²`, one vector `α_k ∈ ℝ³`
//! per mode (Wilson, Taylor, Doherty & Ghaboussi 1973). The modes let the element bend without
//! the parasitic shear that makes the plain trilinear hexahedron lock.
//!
//! Taylor's modification (Taylor, Beresford & Wilson 1976, IJNME 10:1211–1219, eq. 14–16):
//! the mode derivatives are taken with the Jacobian at the element centre, `∇P_k =
//! (det J₀ / det J) J₀⁻¹ ∂P_k/∂ξ`, so that `∫ B_inc dV = det J₀ ∫ J₀⁻¹ ∂P/∂ξ dξ = 0`
//! exactly under 2×2×2 Gauss; the element then reproduces any constant strain on distorted
//! meshes (passes the patch test). The α are condensed statically,
//! `K = K_cc − K_ci K_ii⁻¹ K_ic` (Bathe, *Finite Element Procedures*, 1996, §4.4.1).
//!
//! Stiffness: 2×2×2 Gauss. Each 3×3 block is evaluated in the isotropic closed form
//! `K_ab,ij = ∫ (λ ∂_i N_a ∂_j N_b + G ∂_j N_a ∂_i N_b + G δ_ij ∇N_a·∇N_b) dV`, identical to
//! `∫ Bᵀ D B dV` with `D` from [`IsotropicElastic::elasticity_matrix`] (checked in a test).
//!
//! Consistent mass `ρ ∫ N_a N_b dV` uses 3×3×3 Gauss, exact for any trilinear geometry
//! (integrand of degree ≤ 4 per direction). Lumped mass is HRZ (Hinton, Rock & Zienkiewicz
//! 1976): the diagonal of the consistent mass scaled to the element mass; always positive.
//! The incompatible modes carry no mass.
//!
//! Node order and natural coordinates: see [`crate::mesh`]. DOF order inside the element is
//! node-major: `(u0x, u0y, u0z, u1x, …, u7z)`. Units: coordinates m, moduli Pa, density
//! kg/m³, stiffness N/m, mass kg, energy J.

use nalgebra::{SMatrix, SVector};

use super::material::IsotropicElastic;
use super::FeError;

/// ξ of the eight nodes.
pub(crate) const NODE_XI: [f64; 8] = [-1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0];
/// η of the eight nodes.
pub(crate) const NODE_ETA: [f64; 8] = [-1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0];
/// ζ of the eight nodes.
pub(crate) const NODE_ZETA: [f64; 8] = [-1.0, -1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0];

/// 24 × 24 element matrix (node-major DOFs).
pub(crate) type Mat24 = SMatrix<f64, 24, 24>;

const G2: f64 = 0.577_350_269_189_625_8; // 1/√3

/// Trilinear shape functions `N_a(ξ)` at natural coordinates `xi = [ξ, η, ζ]`.
pub(crate) fn shape_functions(xi: [f64; 3]) -> [f64; 8] {
    let mut n = [0.0; 8];
    for a in 0..8 {
        n[a] = 0.125
            * (1.0 + xi[0] * NODE_XI[a])
            * (1.0 + xi[1] * NODE_ETA[a])
            * (1.0 + xi[2] * NODE_ZETA[a]);
    }
    n
}

/// Natural derivatives `∂N_a/∂ξ_r`, returned as `[r][a]`.
pub(crate) fn shape_derivatives(xi: [f64; 3]) -> [[f64; 8]; 3] {
    let mut d = [[0.0; 8]; 3];
    for a in 0..8 {
        let (p, q, r) = (
            1.0 + xi[0] * NODE_XI[a],
            1.0 + xi[1] * NODE_ETA[a],
            1.0 + xi[2] * NODE_ZETA[a],
        );
        d[0][a] = 0.125 * NODE_XI[a] * q * r;
        d[1][a] = 0.125 * NODE_ETA[a] * p * r;
        d[2][a] = 0.125 * NODE_ZETA[a] * p * q;
    }
    d
}

/// Jacobian `J[r][c] = ∂x_c/∂ξ_r` (m) from natural derivatives.
fn jacobian(coords: &[[f64; 3]; 8], dn: &[[f64; 8]; 3]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for r in 0..3 {
        for a in 0..8 {
            for c in 0..3 {
                j[r][c] += dn[r][a] * coords[a][c];
            }
        }
    }
    j
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Inverse of a 3×3 matrix with known determinant.
fn inv3(m: &[[f64; 3]; 3], det: f64) -> [[f64; 3]; 3] {
    let d = 1.0 / det;
    [
        [
            (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * d,
            (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * d,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * d,
        ],
        [
            (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * d,
            (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * d,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * d,
        ],
        [
            (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * d,
            (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * d,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * d,
        ],
    ]
}

/// Jacobian determinant `det J(ξ)` (m³ per unit natural volume) at a natural point.
pub(crate) fn jacobian_determinant(coords: &[[f64; 3]; 8], xi: [f64; 3]) -> f64 {
    det3(&jacobian(coords, &shape_derivatives(xi)))
}

fn check_det(det_j: f64, xi: [f64; 3]) -> Result<(), FeError> {
    if det_j > 0.0 && det_j.is_finite() {
        Ok(())
    } else {
        Err(FeError::NonPositiveJacobian {
            element: None,
            det_j,
            xi,
        })
    }
}

/// The eight 2×2×2 Gauss points (weights all 1).
fn gauss2() -> [[f64; 3]; 8] {
    let mut p = [[0.0; 3]; 8];
    for (a, pa) in p.iter_mut().enumerate() {
        *pa = [G2 * NODE_XI[a], G2 * NODE_ETA[a], G2 * NODE_ZETA[a]];
    }
    p
}

/// Element stiffness (N/m) of the Wilson–Taylor incompatible-mode hexahedron, 9 internal DOFs
/// condensed. Fails with [`FeError::NonPositiveJacobian`] if `det J ≤ 0` at a Gauss point or
/// the centre, and with [`FeError::InvalidMaterial`] for inadmissible constants.
pub fn stiffness(coords: &[[f64; 3]; 8], mat: &IsotropicElastic) -> Result<Mat24, FeError> {
    stiffness_impl(coords, mat, Modes::WilsonTaylor)
}

/// Element stiffness (N/m) of the *plain* trilinear hexahedron (2×2×2 Gauss, no incompatible
/// modes). It shear-locks in bending; provided for comparison and tests only.
pub fn stiffness_trilinear(
    coords: &[[f64; 3]; 8],
    mat: &IsotropicElastic,
) -> Result<Mat24, FeError> {
    stiffness_impl(coords, mat, Modes::None)
}

/// Which incompatible modes the element carries.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Modes {
    /// Plain trilinear.
    None,
    /// Wilson's original modes, derivatives with the local Jacobian (fails the patch test
    /// on distorted elements; kept only to show that the test detects it).
    #[cfg(test)]
    Wilson,
    /// Wilson's modes with Taylor's centre-Jacobian modification.
    WilsonTaylor,
}

fn stiffness_impl(
    coords: &[[f64; 3]; 8],
    mat: &IsotropicElastic,
    modes: Modes,
) -> Result<Mat24, FeError> {
    let incompatible = modes != Modes::None;
    super::check_material(0, mat)?;
    let lam = mat.lame_lambda();
    let g = mat.shear_modulus();

    // Centre Jacobian for Taylor's modification.
    let j0 = jacobian(coords, &shape_derivatives([0.0; 3]));
    let det0 = det3(&j0);
    check_det(det0, [0.0; 3])?;
    let j0inv = inv3(&j0, det0);

    // 11 "nodes": 8 real + 3 incompatible modes; full 33×33 before condensation.
    let nf = if incompatible { 11 } else { 8 };
    let mut kfull = SMatrix::<f64, 33, 33>::zeros();
    let mut grad = [[0.0f64; 3]; 11];
    for xi in gauss2() {
        let dn = shape_derivatives(xi);
        let j = jacobian(coords, &dn);
        let det = det3(&j);
        check_det(det, xi)?;
        let jinv = inv3(&j, det);
        for a in 0..8 {
            for c in 0..3 {
                grad[a][c] = jinv[c][0] * dn[0][a] + jinv[c][1] * dn[1][a] + jinv[c][2] * dn[2][a];
            }
        }
        if incompatible {
            let (s, jm) = if modes == Modes::WilsonTaylor {
                (det0 / det, &j0inv)
            } else {
                (1.0, &jinv)
            };
            for k in 0..3 {
                // ∂P_k/∂ξ_r = −2 ξ_k δ_rk.
                let dp = -2.0 * xi[k];
                for c in 0..3 {
                    grad[8 + k][c] = s * jm[c][k] * dp;
                }
            }
        }
        let w = det; // Gauss weights are 1.
        for a in 0..nf {
            let ga = grad[a];
            for b in a..nf {
                let gb = grad[b];
                let dot = g * (ga[0] * gb[0] + ga[1] * gb[1] + ga[2] * gb[2]);
                for i in 0..3 {
                    for jj in 0..3 {
                        let mut v = lam * ga[i] * gb[jj] + g * ga[jj] * gb[i];
                        if i == jj {
                            v += dot;
                        }
                        kfull[(3 * a + i, 3 * b + jj)] += w * v;
                    }
                }
            }
        }
    }
    // Mirror the upper block triangle.
    for a in 0..nf {
        for b in a + 1..nf {
            for i in 0..3 {
                for jj in 0..3 {
                    kfull[(3 * b + jj, 3 * a + i)] = kfull[(3 * a + i, 3 * b + jj)];
                }
            }
        }
    }
    let mut k: Mat24 = kfull.fixed_view::<24, 24>(0, 0).into_owned();
    if incompatible {
        let kii: SMatrix<f64, 9, 9> = kfull.fixed_view::<9, 9>(24, 24).into_owned();
        let kci: SMatrix<f64, 24, 9> = kfull.fixed_view::<24, 9>(0, 24).into_owned();
        let chol = kii.cholesky().ok_or(FeError::NonPositiveJacobian {
            element: None,
            det_j: det0,
            xi: [0.0; 3],
        })?;
        let x: SMatrix<f64, 9, 24> = chol.solve(&kci.transpose());
        k -= kci * x;
        // Enforce exact symmetry (round-off of the condensation).
        for r in 0..24 {
            for c in r + 1..24 {
                let v = 0.5 * (k[(r, c)] + k[(c, r)]);
                k[(r, c)] = v;
                k[(c, r)] = v;
            }
        }
    }
    Ok(k)
}

/// Gauss–Legendre 3-point rule on [−1, 1]: (points, weights).
const G3_X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
const G3_W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];

/// Scalar consistent mass `ρ ∫ N_a N_b dV` (kg), 8×8, 3×3×3 Gauss (exact).
pub fn consistent_mass_scalar(
    coords: &[[f64; 3]; 8],
    mat: &IsotropicElastic,
) -> Result<SMatrix<f64, 8, 8>, FeError> {
    super::check_material(0, mat)?;
    let mut m = SMatrix::<f64, 8, 8>::zeros();
    for (i, &x) in G3_X.iter().enumerate() {
        for (j, &y) in G3_X.iter().enumerate() {
            for (l, &z) in G3_X.iter().enumerate() {
                let xi = [x, y, z];
                let det = jacobian_determinant(coords, xi);
                check_det(det, xi)?;
                let w = G3_W[i] * G3_W[j] * G3_W[l] * det * mat.density;
                let n = shape_functions(xi);
                for a in 0..8 {
                    for b in a..8 {
                        m[(a, b)] += w * n[a] * n[b];
                    }
                }
            }
        }
    }
    for a in 0..8 {
        for b in a + 1..8 {
            m[(b, a)] = m[(a, b)];
        }
    }
    Ok(m)
}

/// Consistent mass matrix (kg), 24×24, node-major DOFs: `M = ρ ∫ Nᵀ N dV` (3×3×3 Gauss, exact).
pub fn consistent_mass(coords: &[[f64; 3]; 8], mat: &IsotropicElastic) -> Result<Mat24, FeError> {
    let ms = consistent_mass_scalar(coords, mat)?;
    let mut m = Mat24::zeros();
    for a in 0..8 {
        for b in 0..8 {
            for d in 0..3 {
                m[(3 * a + d, 3 * b + d)] = ms[(a, b)];
            }
        }
    }
    Ok(m)
}

/// HRZ-lumped nodal masses (kg), one per node, acting in each of the three directions:
/// `m_a = M_aa · (ρV / Σ_b M_bb)` with `M` the scalar consistent mass. Sums to `ρV`.
pub fn lumped_mass(coords: &[[f64; 3]; 8], mat: &IsotropicElastic) -> Result<[f64; 8], FeError> {
    let ms = consistent_mass_scalar(coords, mat)?;
    let total = ms.sum();
    let diag: f64 = (0..8).map(|a| ms[(a, a)]).sum();
    let mut out = [0.0; 8];
    if diag > 0.0 {
        for (a, o) in out.iter_mut().enumerate() {
            *o = ms[(a, a)] * total / diag;
        }
    }
    Ok(out)
}

/// Element volume (m³), `∫ det J dξ` by 2×2×2 Gauss (exact for trilinear geometry).
pub fn volume(coords: &[[f64; 3]; 8]) -> Result<f64, FeError> {
    let mut v = 0.0;
    for xi in gauss2() {
        let det = jacobian_determinant(coords, xi);
        check_det(det, xi)?;
        v += det;
    }
    Ok(v)
}

/// Physical position `x(ξ) = Σ N_a(ξ) x_a` (m) of a natural point.
pub fn map_to_physical(coords: &[[f64; 3]; 8], xi: [f64; 3]) -> [f64; 3] {
    interpolate_vector(&shape_functions(xi), coords)
}

/// Interpolates a vector nodal field (e.g. a mode shape's nodal displacements) with
/// precomputed shape-function values `n = shape_functions(ξ)`.
pub fn interpolate_vector(n: &[f64; 8], values: &[[f64; 3]; 8]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for a in 0..8 {
        for c in 0..3 {
            out[c] += n[a] * values[a][c];
        }
    }
    out
}

/// Interpolates a scalar nodal field with shape-function values `n = shape_functions(ξ)`.
pub fn interpolate_scalar(n: &[f64; 8], values: &[f64; 8]) -> f64 {
    n.iter().zip(values).map(|(a, b)| a * b).sum()
}

/// Natural coordinates `ξ` of a physical point `p` (m), found by Newton iteration on
/// `x(ξ) = p` from the centre. Converges for points inside or near any valid element; it
/// does not check inclusion: the point is inside iff every `|ξ_i| ≤ 1` (use [`is_inside`]).
/// Fails with [`FeError::NewtonNotConverged`] after 50 iterations or on a singular Jacobian.
pub fn natural_coordinates(coords: &[[f64; 3]; 8], p: [f64; 3]) -> Result<[f64; 3], FeError> {
    // Characteristic size for the tolerance.
    let v = volume(coords)?;
    let tol = 1e-13 * v.cbrt();
    let mut xi = [0.0f64; 3];
    let mut res = f64::INFINITY;
    const MAX_IT: usize = 50;
    for _ in 0..MAX_IT {
        let x = map_to_physical(coords, xi);
        let r = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
        res = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if res <= tol {
            return Ok(xi);
        }
        let j = jacobian(coords, &shape_derivatives(xi));
        let det = det3(&j);
        if det == 0.0 || !det.is_finite() {
            break;
        }
        let ji = inv3(&j, det);
        // dx = Jᵀ dξ  ⇒  dξ = J⁻ᵀ r,  (J⁻ᵀ)[r][c] = ji[c][r].
        for rr in 0..3 {
            xi[rr] += ji[0][rr] * r[0] + ji[1][rr] * r[1] + ji[2][rr] * r[2];
        }
        if xi.iter().any(|v| !v.is_finite() || v.abs() > 1e3) {
            break;
        }
    }
    Err(FeError::NewtonNotConverged {
        point: p,
        iterations: MAX_IT,
        residual: res,
    })
}

/// True when natural coordinates lie inside the element, `|ξ_i| ≤ 1 + tol`.
pub fn is_inside(xi: [f64; 3], tol: f64) -> bool {
    xi.iter().all(|v| v.abs() <= 1.0 + tol)
}

/// Strain energy `½ uᵀ K u` (J) of an element stiffness `k` (N/m) for element displacements
/// `u` (m, node-major).
pub(crate) fn strain_energy_of(k: &Mat24, u: &[f64; 24]) -> f64 {
    let u = SVector::<f64, 24>::from_column_slice(u);
    0.5 * u.dot(&(k * u))
}

/// Strain energy `½ uᵀ K u` (J) of one element for element displacements `u` (m,
/// node-major), computing the stiffness.
pub fn strain_energy(
    coords: &[[f64; 3]; 8],
    mat: &IsotropicElastic,
    u: &[f64; 24],
) -> Result<f64, FeError> {
    Ok(strain_energy_of(&stiffness(coords, mat)?, u))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::{
        consistent_mass, consistent_mass_scalar, det3, gauss2, interpolate_vector, inv3, is_inside,
        jacobian, jacobian_determinant, lumped_mass, map_to_physical, natural_coordinates,
        shape_derivatives, shape_functions, stiffness, stiffness_impl, stiffness_trilinear,
        strain_energy, strain_energy_of, volume, FeError, IsotropicElastic, Mat24, Modes, SMatrix,
        SVector, NODE_ETA, NODE_XI, NODE_ZETA,
    };
    /// A distorted, non-parallelepiped hexahedron (for tests in this module and others).
    pub(crate) fn distorted() -> [[f64; 3]; 8] {
        [
            [0.0, 0.0, 0.0],
            [1.2, 0.1, -0.05],
            [1.3, 1.1, 0.1],
            [-0.1, 0.9, 0.05],
            [0.1, -0.05, 0.9],
            [1.1, 0.05, 1.2],
            [1.25, 1.2, 1.0],
            [0.05, 1.0, 1.1],
        ]
    }

    fn unit_cube() -> [[f64; 3]; 8] {
        let mut c = [[0.0; 3]; 8];
        for a in 0..8 {
            c[a] = [
                0.5 * (1.0 + NODE_XI[a]),
                0.5 * (1.0 + NODE_ETA[a]),
                0.5 * (1.0 + NODE_ZETA[a]),
            ];
        }
        c
    }

    #[test]
    fn shape_functions_partition_of_unity_and_kronecker() {
        let n = shape_functions([0.3, -0.7, 0.2]);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for a in 0..8 {
            let na = shape_functions([NODE_XI[a], NODE_ETA[a], NODE_ZETA[a]]);
            for (b, &v) in na.iter().enumerate() {
                assert_eq!(v, if a == b { 1.0 } else { 0.0 });
            }
        }
    }

    #[test]
    fn volume_of_cube_and_distorted_matches_divergence_theorem() {
        assert!((volume(&unit_cube()).unwrap() - 1.0).abs() < 1e-14);
        // Independent volume: sum of 6 tetrahedra would need planar faces; instead use a
        // 10×10×10 midpoint-free check with a 5-point Gauss rule per direction.
        let c = distorted();
        let (x5, w5) = (
            [
                -0.906_179_845_938_664,
                -0.538_469_310_105_683,
                0.0,
                0.538_469_310_105_683,
                0.906_179_845_938_664,
            ],
            [
                0.236_926_885_056_189,
                0.478_628_670_499_366,
                0.568_888_888_888_889,
                0.478_628_670_499_366,
                0.236_926_885_056_189,
            ],
        );
        let mut v = 0.0;
        for i in 0..5 {
            for j in 0..5 {
                for k in 0..5 {
                    v += w5[i] * w5[j] * w5[k] * jacobian_determinant(&c, [x5[i], x5[j], x5[k]]);
                }
            }
        }
        assert!(
            (volume(&c).unwrap() - v).abs() / v < 1e-12,
            "{} vs {v}",
            volume(&c).unwrap()
        );
    }

    #[test]
    fn inverted_element_is_an_error() {
        let mut c = unit_cube();
        c.swap(0, 4);
        c.swap(1, 5);
        c.swap(2, 6);
        c.swap(3, 7);
        let e = stiffness(&c, &IsotropicElastic::STEEL).unwrap_err();
        assert!(matches!(e, FeError::NonPositiveJacobian { .. }), "{e}");
        assert!(volume(&c).is_err());
    }

    #[test]
    fn closed_form_blocks_equal_bt_d_b() {
        // The isotropic block formula must equal ∫ Bᵀ D B with D from elasticity_matrix().
        let c = distorted();
        let m = IsotropicElastic {
            youngs_modulus: 3.0e9,
            poisson_ratio: 0.27,
            density: 2000.0,
        };
        let d = m.elasticity_matrix();
        let mut kref = Mat24::zeros();
        for xi in gauss2() {
            let dn = shape_derivatives(xi);
            let j = jacobian(&c, &dn);
            let det = det3(&j);
            let ji = inv3(&j, det);
            let mut b = SMatrix::<f64, 6, 24>::zeros();
            for a in 0..8 {
                let g: Vec<f64> = (0..3)
                    .map(|cc| ji[cc][0] * dn[0][a] + ji[cc][1] * dn[1][a] + ji[cc][2] * dn[2][a])
                    .collect();
                b[(0, 3 * a)] = g[0];
                b[(1, 3 * a + 1)] = g[1];
                b[(2, 3 * a + 2)] = g[2];
                b[(3, 3 * a + 1)] = g[2];
                b[(3, 3 * a + 2)] = g[1];
                b[(4, 3 * a)] = g[2];
                b[(4, 3 * a + 2)] = g[0];
                b[(5, 3 * a)] = g[1];
                b[(5, 3 * a + 1)] = g[0];
            }
            kref += b.transpose() * d * b * det;
        }
        let k = stiffness_trilinear(&c, &m).unwrap();
        let err = (k - kref).abs().max() / kref.abs().max();
        assert!(err < 1e-13, "relative difference {err:e}");
    }

    fn rigid_body_zero_count(k: &Mat24) -> (usize, f64) {
        let ev = k.symmetric_eigenvalues();
        let max = ev.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let mut v: Vec<f64> = ev.iter().map(|x| x / max).collect();
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let zeros = v.iter().filter(|x| x.abs() < 1e-10).count();
        (zeros, v[6])
    }

    #[test]
    fn free_element_has_exactly_six_rigid_body_modes() {
        // Dense eigenvalues of K (nalgebra symmetric eigen, an independent solver):
        // six zero (relative to the largest < 1e-10), the seventh clearly positive.
        for c in [unit_cube(), distorted()] {
            let k = stiffness(&c, &IsotropicElastic::STEEL).unwrap();
            let (zeros, seventh) = rigid_body_zero_count(&k);
            assert_eq!(zeros, 6);
            assert!(seventh > 1e-4, "seventh eigenvalue/max = {seventh:e}");
            // Symmetric.
            assert!((k - k.transpose()).abs().max() < 1e-12 * k.abs().max());
        }
    }

    #[test]
    fn single_distorted_element_reproduces_constant_strain_energy() {
        // A linear field u = A x has constant strain ε(A); for every element that passes the
        // patch test the condensed stiffness gives ½ uᵀKu = ½ ε·Dε V exactly (the incompatible
        // modes are not activated by a constant strain).
        let c = distorted();
        let m = IsotropicElastic::STEEL;
        let a = [
            [1e-3, 2e-4, -3e-4],
            [5e-4, -7e-4, 1e-4],
            [-2e-4, 3e-4, 6e-4],
        ];
        let mut u = [0.0; 24];
        for n in 0..8 {
            for i in 0..3 {
                u[3 * n + i] = (0..3).map(|j| a[i][j] * c[n][j]).sum();
            }
        }
        let eps = SVector::<f64, 6>::from_column_slice(&[
            a[0][0],
            a[1][1],
            a[2][2],
            a[1][2] + a[2][1],
            a[0][2] + a[2][0],
            a[0][1] + a[1][0],
        ]);
        let exact = 0.5 * eps.dot(&(m.elasticity_matrix() * eps)) * volume(&c).unwrap();
        let got = strain_energy(&c, &m, &u).unwrap();
        assert!((got - exact).abs() / exact < 1e-12, "{got} vs {exact}");
        // Without Taylor's modification the modes couple to the constant strain on this
        // distorted element and lower the energy: the check above detects it.
        let kw = stiffness_impl(&c, &m, Modes::Wilson).unwrap();
        let wrong = strain_energy_of(&kw, &u);
        eprintln!(
            "constant-strain energy: Wilson–Taylor error {:.2e}, Wilson without Taylor {:.2e}",
            (got - exact) / exact,
            (wrong - exact) / exact
        );
        assert!(
            (exact - wrong) / exact > 1e-4,
            "Wilson without Taylor: {wrong} vs {exact}"
        );
        // On a parallelepiped both variants coincide.
        let cube = unit_cube();
        let d = (stiffness_impl(&cube, &m, Modes::Wilson).unwrap() - stiffness(&cube, &m).unwrap())
            .abs()
            .max();
        assert!(d < 1e-12 * stiffness(&cube, &m).unwrap().abs().max());
    }

    #[test]
    fn mass_totals_equal_rho_v() {
        let c = distorted();
        let m = IsotropicElastic::STEEL;
        let rv = m.density * volume(&c).unwrap();
        let mc = consistent_mass(&c, &m).unwrap();
        // Translation in x: 1ᵀ M 1 over x DOFs = ρ V.
        let mut tx = 0.0;
        for a in 0..8 {
            for b in 0..8 {
                tx += mc[(3 * a, 3 * b)];
            }
        }
        assert!((tx - rv).abs() / rv < 1e-13);
        let ml = lumped_mass(&c, &m).unwrap();
        assert!((ml.iter().sum::<f64>() - rv).abs() / rv < 1e-13);
        assert!(ml.iter().all(|&x| x > 0.0));
        // Cube: HRZ gives ρV/8 at every node.
        let ml = lumped_mass(&unit_cube(), &m).unwrap();
        for x in ml {
            assert!((x - m.density / 8.0).abs() < 1e-10);
        }
    }

    #[test]
    fn box_consistent_mass_is_tensor_product_of_bar_masses() {
        // Closed form for a rectangular box: the 1D linear-element mass (ρAh/6)[2 1; 1 2] in
        // each direction, so M_ab = ρV/216 · Π_d (2 if node a and b share coordinate d, else 1).
        let (lx, ly, lz) = (0.3, 0.2, 0.05);
        let c: [[f64; 3]; 8] = std::array::from_fn(|a| {
            [
                0.5 * lx * (1.0 + NODE_XI[a]),
                0.5 * ly * (1.0 + NODE_ETA[a]),
                0.5 * lz * (1.0 + NODE_ZETA[a]),
            ]
        });
        let m = IsotropicElastic::STEEL;
        let rv = m.density * lx * ly * lz;
        let ms = consistent_mass_scalar(&c, &m).unwrap();
        for a in 0..8 {
            for b in 0..8 {
                let f = |x: &[f64; 8]| if x[a] == x[b] { 2.0 } else { 1.0 };
                let exact = rv / 216.0 * f(&NODE_XI) * f(&NODE_ETA) * f(&NODE_ZETA);
                assert!((ms[(a, b)] - exact).abs() < 1e-13 * rv, "({a},{b})");
            }
        }
    }

    #[test]
    fn newton_recovers_natural_coordinates() {
        let c = distorted();
        for xi in [[0.3, -0.6, 0.9], [-1.0, 1.0, 0.0], [0.99, 0.01, -0.95]] {
            let p = map_to_physical(&c, xi);
            let got = natural_coordinates(&c, p).unwrap();
            for i in 0..3 {
                assert!((got[i] - xi[i]).abs() < 1e-12, "{got:?} vs {xi:?}");
            }
            assert!(is_inside(got, 1e-9));
        }
        // Outside point: found but flagged outside.
        let p = map_to_physical(&c, [1.5, 0.0, 0.0]);
        let got = natural_coordinates(&c, p).unwrap();
        assert!(!is_inside(got, 1e-9));
        // Interpolating the coordinates themselves returns the point (isoparametric).
        let n = shape_functions([0.3, -0.6, 0.9]);
        let p2 = interpolate_vector(&n, &c);
        let p1 = map_to_physical(&c, [0.3, -0.6, 0.9]);
        assert_eq!(p1, p2);
    }
}
