//! The elastic static flexibility of a free (floating) body by inertia relief, shared by the
//! reduced engine's wheel residual flexibility (docs/theory.md §7.7) and the explicit path's
//! rotating wheel (§8.8).
//!
//! A free body's `K` is singular (its rigid-body modes span the null space), so its static
//! flexibility is the **elastic** one (Craig & Kurdila 2006; Géradin & Rixen 2015):
//! `P = I − M Φ_r Φ_rᵀ` removes the rigid part of a load (`Φ_rᵀ M Φ_r = I`), and
//! `G_e = Pᵀ K_c⁻¹ P = Σ_{elastic i} φ_i φ_iᵀ / ω_i²` (m/N), with `K_c` the stiffness held at
//! as many DOFs as there are rigid modes, chosen so that they fix the rigid motion in a
//! statically determinate way: a balanced load `P b` has no reactions there, so the holding
//! springs' size does not matter and `K_c⁻¹ P b` differs from the free body's elastic
//! deflection by a rigid motion only, which `Pᵀ` removes.

use faer::sparse::SparseColMatRef;
use faer::Mat;

use super::contact_line::dot;
use super::statics::StiffnessFactor;
use super::PassageError;

/// Rayleigh quotient `rᵀKr` (rad²/s²) below which a mass-normalised rigid-body mode of the
/// basis is in the null space of `K` (0.016 Hz; the passage's rigid threshold is 0.5 Hz).
const NULL_OMEGA2: f64 = 1e-2;

/// `y = A x` for a sparse matrix in full storage.
fn spmv(a: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64]) {
    let (cp, ri, v) = (a.symbolic().col_ptr(), a.symbolic().row_idx(), a.val());
    y.iter_mut().for_each(|e| *e = 0.0);
    for j in 0..a.ncols() {
        let xj = x[j];
        if xj != 0.0 {
            for p in cp[j]..cp[j + 1] {
                y[ri[p]] += v[p] * xj;
            }
        }
    }
}

/// The rigid-body columns of `modes` (ω² = 0), M-orthonormalised (Gram–Schmidt), with `M Φ_r`.
fn rigid_modes(
    m: SparseColMatRef<'_, usize, f64>,
    modes: &Mat<f64>,
    omega2: &[f64],
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let n = modes.nrows();
    let mut rig: Vec<Vec<f64>> = Vec::new();
    let mut mrig: Vec<Vec<f64>> = Vec::new();
    let mut mr = vec![0.0; n];
    for i in (0..omega2.len()).filter(|&i| omega2[i] == 0.0) {
        let mut r: Vec<f64> = (0..n).map(|d| modes[(d, i)]).collect();
        for (q, mq) in rig.iter().zip(&mrig) {
            let c = dot(mq, &r);
            r.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
        }
        spmv(m, &r, &mut mr);
        let nn = dot(&mr, &r).sqrt();
        if nn > 0.0 {
            r.iter_mut().for_each(|x| *x /= nn);
            mrig.push(mr.iter().map(|x| x / nn).collect());
            rig.push(r);
        }
    }
    (rig, mrig)
}

/// DOFs that hold the rigid modes in a statically determinate way: pivoted Gram–Schmidt on
/// the rows of `Φ_r` (the DOF whose row is largest after removing the span of those already
/// chosen), over the DOFs not in `exclude`.
fn determinate_supports(rig: &[Vec<f64>], exclude: &[usize]) -> Vec<usize> {
    let nr = rig.len();
    let n = rig.first().map_or(0, Vec::len);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut chosen = Vec::new();
    for _ in 0..nr {
        let residual = |d: usize| -> Vec<f64> {
            let mut row: Vec<f64> = rig.iter().map(|r| r[d]).collect();
            for b in &basis {
                let c = dot(b, &row);
                row.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
            }
            row
        };
        let best = (0..n)
            .filter(|d| !exclude.contains(d) && !chosen.contains(d))
            .map(|d| (d, dot(&residual(d), &residual(d))))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((d, norm2)) = best else { break };
        if norm2 <= 0.0 {
            break;
        }
        let mut row = residual(d);
        let nn = norm2.sqrt();
        row.iter_mut().for_each(|x| *x /= nn);
        basis.push(row);
        chosen.push(d);
    }
    chosen
}

/// A free (floating) structure: stiffness and mass over its free DOFs, and a modal basis
/// whose rigid-body modes (ω² = 0) span the null space of `K`.
#[derive(Clone, Copy)]
pub struct FreeBody<'a> {
    /// Stiffness (N/m, full symmetric storage).
    pub k: SparseColMatRef<'a, usize, f64>,
    /// Mass (kg, full symmetric storage).
    pub m: SparseColMatRef<'a, usize, f64>,
    /// Mass-normalised modes (DOFs × modes), the rigid-body ones among them.
    pub modes: &'a Mat<f64>,
    /// Their ω² (rad²/s²), exactly 0 for the rigid-body modes.
    pub omega2: &'a [f64],
    /// DOFs not to hold (e.g. a mass on a soft spring).
    pub exclude: &'a [usize],
}

/// The elastic static flexibility `G_ab = b_aᵀ Pᵀ K_c⁻¹ P b_b` (m/N) between the `loads`
/// (free-DOF vectors) of a free body, by inertia relief (see the module documentation): one sparse LDLᵀ of `K`
/// held at statically determinate DOFs. Equals `Σ_{elastic} (φᵀb_a)(φᵀb_b)/ω²` over all the
/// body's modes.
pub fn elastic_flexibility(
    body: FreeBody<'_>,
    loads: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, PassageError> {
    let n = body.k.nrows();
    let (rig, mrig) = rigid_modes(body.m, body.modes, body.omega2);
    // The supports hold the null space of K only: a mode the basis counts as rigid but that
    // K does not (a suspension bounce below the rigid-mode threshold) is projected out by P
    // like the rigid ones, but holding it too would over-constrain the body.
    let mut kr = vec![0.0; n];
    let null: Vec<Vec<f64>> = rig
        .iter()
        .filter(|r| {
            spmv(body.k, r, &mut kr);
            dot(r, &kr) < NULL_OMEGA2
        })
        .cloned()
        .collect();
    let held = determinate_supports(&null, body.exclude);
    let factor = held_factor(body.k, &held)?;
    let nl = loads.len();
    let mut rhs = Mat::<f64>::zeros(n, nl);
    let mut balanced = Vec::with_capacity(nl);
    for (j, b) in loads.iter().enumerate() {
        let mut pb = b.clone();
        for (r, mr) in rig.iter().zip(&mrig) {
            let c = dot(r, b);
            pb.iter_mut().zip(mr).for_each(|(x, y)| *x -= c * y);
        }
        for (i, &v) in pb.iter().enumerate() {
            rhs[(i, j)] = v;
        }
        balanced.push(pb);
    }
    let mut ws = factor.workspace(nl.max(1));
    factor.solve_in_place(rhs.as_mut(), &mut ws);
    Ok((0..nl)
        .map(|a| {
            (0..nl)
                .map(|b| (0..n).map(|i| balanced[a][i] * rhs[(i, b)]).sum())
                .collect()
        })
        .collect())
}

/// The sparse LDLᵀ of `K` with stiff springs (the mean diagonal of K) at the `held` DOFs.
fn held_factor(
    k: SparseColMatRef<'_, usize, f64>,
    held: &[usize],
) -> Result<StiffnessFactor, PassageError> {
    let (cp, ri) = (k.symbolic().col_ptr(), k.symbolic().row_idx());
    let diag: Vec<usize> = (0..k.ncols())
        .filter_map(|j| (cp[j]..cp[j + 1]).find(|&p| ri[p] == j))
        .collect();
    if diag.len() != k.ncols() {
        return Err(PassageError::MissingNodes {
            what: "diagonal entry in every column of the wheel's stiffness",
        });
    }
    let mean = diag.iter().map(|&p| k.val()[p]).sum::<f64>() / diag.len() as f64;
    let sym = k
        .symbolic()
        .to_owned()
        .map_err(|source| PassageError::WheelStiffnessCopy { source })?;
    let mut vals = k.val().to_vec();
    for &d in held {
        vals[diag[d]] += mean;
    }
    let ks = faer::sparse::SparseColMat::new(sym, vals);
    StiffnessFactor::new(ks.as_ref())
}
