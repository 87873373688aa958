//! The rotating wheel's local compliance under the contact carried round its faceted tread,
//! and its removal from the contact (docs/theory.md §8.7).
//!
//! The rotating wheel applies the contact force to the tread nodes of the two angle planes
//! around the contact's material angle `φ`, interpolated linearly in angle (weights
//! `1 − s`, `s`), and reads the displacement there with the same weights. Under that load,
//! per unit force in contact-frame direction `d` (ground direction `a_d`, spinning-frame
//! components `a_d(φ) = Qᵀ(φ) a_d`), the wheel's elastic static displacement at the contact
//! is the quadratic form
//!
//! ```text
//! g_d(φ) = a_d(φ)ᵀ [ (1−s)² C_jj + s(1−s) (C_j,j+1 + C_j,j+1ᵀ) + s² C_j+1,j+1 ] a_d(φ)   (m/N)
//! C_jk[c][c'] = b_{j,c}ᵀ G_e b_{k,c'}
//! ```
//!
//! with `b_{j,c}` the unit Cartesian load `c` on the tread nodes of angle plane `j` and `G_e`
//! the wheel's elastic flexibility by inertia relief, the supports and suspension of the
//! wheel's static start ([`crate::explicit::start::ElasticWheel`]). The physical wheel is
//! axisymmetric: its local compliance does not depend on `φ`. On the mesh it does, because
//! the load's share between two planes changes inside each tread segment and the mesh is
//! graded in angle (finest at θ = 0), so `g_d(φ) − g_d(0)` is a discretisation artefact.
//! The reference `g_d(0)` is the compliance at the fixed wheel's contact, so that with the
//! removal the rotating wheel's contact sees the fixed wheel's compliance at every angle.

use super::{OnWheel, PlaneNodes};
use crate::explicit::start::ElasticWheel;
use crate::explicit::ExplicitError;

/// A 3×3 compliance block between two angle planes (m/N, spinning-frame Cartesian).
type Block = [[f64; 3]; 3];

/// Loads solved together (memory `n × 3·PLANES_PER_SOLVE × 8` bytes).
const PLANES_PER_SOLVE: usize = 8;

/// The compliance blocks of the angle planes the contact travels through, and the
/// reference compliance `g_d(0)`.
#[derive(Clone, Debug)]
pub(crate) struct WheelLocalCompliance {
    /// Per angle plane `k`: `C_kk` and `C_k,k+1` (the next plane in angle, cyclically);
    /// `None` where the contact does not travel.
    diag: Vec<Option<Block>>,
    cross: Vec<Option<Block>>,
    /// The contact frame's axes in ground components.
    axes: [[f64; 3]; 3],
    /// `g_d` at θ = 0 (m/N).
    reference: [f64; 3],
    /// The last angle covered (rad, from θ = 0 in the direction of travel).
    phi_max: f64,
}

/// Reads the Cartesian displacement of plane `nodes` (weighted) from `u`.
fn read(nodes: &PlaneNodes, u: &[f64]) -> [f64; 3] {
    let mut d = [0.0; 3];
    for &(idx, wt) in nodes {
        for c in 0..3 {
            if idx[c] != usize::MAX {
                d[c] += wt * u[idx[c]];
            }
        }
    }
    d
}

impl WheelLocalCompliance {
    /// The blocks for a contact travelling from θ = 0 through the angle `phi_max` (rad; a
    /// full turn or more covers every plane), from the wheel's angle planes `planes` at
    /// `thetas` (rad, increasing, θ = 0 at index `k0`), the elastic solver `elastic` and the
    /// contact frame's `axes`: one block solve per `PLANES_PER_SOLVE` planes.
    pub(crate) fn compute(
        elastic: &ElasticWheel,
        planes: &[PlaneNodes],
        (thetas, k0): (&[f64], usize),
        axes: [[f64; 3]; 3],
        phi_max: f64,
        n: usize,
    ) -> Result<Self, ExplicitError> {
        let nt = planes.len();
        // Planes k0, k0 + 1, ... up to the one past phi_max (cyclically).
        let last = super::locate_angle(thetas, phi_max.max(0.0));
        let span = (last.j + 1 - k0 as i64).clamp(0, nt as i64) as usize;
        let needed: Vec<usize> = (0..=span.min(nt - 1)).map(|i| (k0 + i) % nt).collect();
        let mut diag = vec![None; nt];
        let mut cross = vec![None; nt];
        for chunk in needed.chunks(PLANES_PER_SOLVE) {
            let mut loads: Vec<Vec<f64>> = Vec::with_capacity(3 * chunk.len());
            for &k in chunk {
                for c in 0..3 {
                    let mut b = vec![0.0; n];
                    for &(idx, wt) in &planes[k] {
                        if idx[c] != usize::MAX {
                            b[idx[c]] += wt;
                        }
                    }
                    loads.push(b);
                }
            }
            elastic.solve_many(&mut loads);
            for (i, &k) in chunk.iter().enumerate() {
                let u = &loads[3 * i..3 * i + 3];
                let block = |nodes: &PlaneNodes| -> Block { [0, 1, 2].map(|c| read(nodes, &u[c])) };
                diag[k] = Some(block(&planes[k]));
                cross[k] = Some(block(&planes[(k + 1) % nt]));
            }
        }
        let mut lc = WheelLocalCompliance {
            diag,
            cross,
            axes,
            reference: [0.0; 3],
            phi_max: if span + 1 >= nt {
                f64::INFINITY
            } else {
                phi_max
            },
        };
        let at0 = super::locate_angle(thetas, 0.0);
        lc.reference = lc.g(at0).ok_or(ExplicitError::Static {
            part: "wheel",
            reason: "the tread's local compliance at θ = 0 was not computed".into(),
        })?;
        Ok(lc)
    }

    /// The last angle covered (rad; infinite when every plane is).
    pub(crate) fn phi_max(&self) -> f64 {
        self.phi_max
    }

    /// `g_d` (m/N per contact-frame direction) with the contact at `at`; `None` where the
    /// blocks were not computed.
    pub(super) fn g(&self, at: OnWheel) -> Option<[f64; 3]> {
        let nt = self.diag.len() as i64;
        let j = at.j.rem_euclid(nt) as usize;
        let j1 = (at.j + 1).rem_euclid(nt) as usize;
        let (a, b, x) = (self.diag[j]?, self.diag[j1]?, self.cross[j]?);
        let s = at.s;
        let (wa, wb, wx) = ((1.0 - s) * (1.0 - s), s * s, s * (1.0 - s));
        Some(self.axes.map(|ax| {
            let ar = super::to_spinning(at.cs, ax);
            let mut g = 0.0;
            for c in 0..3 {
                for cp in 0..3 {
                    let m = wa * a[c][cp] + wb * b[c][cp] + wx * (x[c][cp] + x[cp][c]);
                    g += ar[c] * m * ar[cp];
                }
            }
            g
        }))
    }

    /// `g_d(φ) − g_d(0)` (m/N) with the contact at `at`; `None` where not computed.
    pub(super) fn variation(&self, at: OnWheel) -> Option<[f64; 3]> {
        let g = self.g(at)?;
        Some([0, 1, 2].map(|d| g[d] - self.reference[d]))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{locate_angle, to_spinning};
    use crate::dynamics::reduced::add_nodes_load;
    use crate::dynamics::wheel_residual::{elastic_flexibility, FreeBody};
    use crate::explicit::{ExplicitModel, ExplicitOptions};
    use crate::model::{load_model, test_problems::SMALL_MODEL, ExplicitWheel, ModelSource};
    use faer::Mat;

    /// The tread compliance `g_d(φ)` at angle planes and between them against an independent
    /// inertia-relief solve over the wheel body's mass (`elastic_flexibility`: its own
    /// statically determinate supports, Gram–Schmidt and factorisation) of the
    /// angle-interpolated load on the small wheel; the compliance
    /// with the variation removed is the reference at every angle, and the reference is the
    /// fixed wheel's compliance at its contact. The variation itself is not small (so the
    /// test can tell a removal from none).
    #[test]
    fn tread_compliance_matches_a_direct_inertia_relief_solve() {
        let sets: Vec<String> = SMALL_MODEL.iter().map(|s| s.to_string()).collect();
        let model = load_model(&ModelSource::Builtin, &sets).unwrap();
        let opts = ExplicitOptions {
            wheel: ExplicitWheel::Rotating,
            ..ExplicitOptions::default()
        };
        let em = ExplicitModel::new(&model, opts).unwrap();
        let lc = em.wheel_local.as_ref().unwrap();
        let w = &em.wheel_structure;
        let (fm, _) = w.assemble().unwrap();
        let n = w.dofmap.n_free();
        let modes = Mat::from_fn(n, em.rigid.len(), |i, k| em.rigid[k][i]);
        let omega2 = vec![0.0; em.rigid.len()];
        let sprung: Vec<usize> = (0..3)
            .filter_map(|c| w.dofmap.free_index(3 * w.sprung_node + c))
            .collect();
        // The wheel body's mass: the sprung mass gets no inertial share.
        let mut mb = fm.m.clone();
        {
            let (cp, ri) = (
                mb.symbolic().col_ptr().to_vec(),
                mb.symbolic().row_idx().to_vec(),
            );
            let vals = mb.val_mut();
            for &d in &sprung {
                for p in cp[d]..cp[d + 1] {
                    vals[p] = 0.0;
                }
                for j in 0..n {
                    for p in cp[j]..cp[j + 1] {
                        if ri[p] == d {
                            vals[p] = 0.0;
                        }
                    }
                }
            }
        }
        let body = FreeBody {
            k: fm.k.as_ref(),
            m: mb.as_ref(),
            modes: &modes,
            omega2: &omega2,
            exclude: &sprung,
        };
        let planes = super::super::tread_planes(w, &em.wheel_nodes).unwrap();
        let topo = &w.topology;
        let (th, k0) = (&topo.thetas, topo.contact_angle_index());
        let axes = [em.frame.x, em.frame.t, em.frame.n];
        // Plane angles and points between them, over the fine zone and the coarse segments.
        let mut phis = Vec::new();
        for k in [k0, k0 + 1, k0 + 2, k0 + 5, k0 + 8] {
            phis.push(th[k]);
            phis.push(th[k] + 0.37 * (th[k + 1] - th[k]));
        }
        let mut loads = Vec::new();
        for &phi in &phis {
            let at = locate_angle(th, phi);
            for ax in axes {
                let ar = to_spinning(at.cs, ax);
                let mut b = vec![0.0; n];
                for (j, wj) in [(at.j, 1.0 - at.s), (at.j + 1, at.s)] {
                    for &(idx, wt) in &planes[j.rem_euclid(th.len() as i64) as usize] {
                        for c in 0..3 {
                            if idx[c] != usize::MAX {
                                b[idx[c]] += wj * wt * ar[c];
                            }
                        }
                    }
                }
                loads.push(b);
            }
        }
        // The fixed wheel's contact load.
        for d in 0..3 {
            let mut force = [0.0; 3];
            force[d] = 1.0;
            let mut b = vec![0.0; n];
            add_nodes_load(&em.wheel_nodes, &w.dofmap, &em.frame, 1.0, force, &mut b);
            loads.push(b);
        }
        let direct = elastic_flexibility(body, &loads).unwrap();
        let g_ref = lc.reference;
        let mut largest: f64 = 0.0;
        for (i, &phi) in phis.iter().enumerate() {
            let at = locate_angle(th, phi);
            let g = lc.g(at).unwrap();
            let dg = lc.variation(at).unwrap();
            for d in 0..3 {
                let gd = direct[3 * i + d][3 * i + d];
                assert!(
                    (g[d] - gd).abs() <= 1e-8 * gd.abs(),
                    "φ {phi} d {d}: {} vs direct {gd}",
                    g[d]
                );
                let corrected = gd - dg[d];
                assert!(
                    (corrected - g_ref[d]).abs() <= 1e-8 * g_ref[d],
                    "φ {phi} d {d}: corrected {corrected} vs reference {}",
                    g_ref[d]
                );
                largest = largest.max(dg[d].abs() / g_ref[d]);
            }
        }
        let nf = 3 * phis.len();
        for d in 0..3 {
            let gf = direct[nf + d][nf + d];
            assert!(
                (g_ref[d] - gf).abs() <= 1e-8 * gf,
                "d {d}: reference {} vs the fixed wheel's {gf}",
                g_ref[d]
            );
        }
        eprintln!(
            "tread compliance: reference {g_ref:?} m/N, largest variation {largest:.3} of it"
        );
        assert!(largest > 0.05, "variation only {largest}");
    }
}
