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
    /// Per angle plane `k`: `C_kk`, `C_k,k+1` and `C_k,k+2` (the next planes in angle,
    /// cyclically; `[c][c']` the displacement along `c'` at the other plane under a unit
    /// load along `c` at `k`); `None` where the contact does not travel.
    diag: Vec<Option<Block>>,
    cross: Vec<Option<Block>>,
    cross2: Vec<Option<Block>>,
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
        let mut cross2 = vec![None; nt];
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
                cross2[k] = Some(block(&planes[(k + 2) % nt]));
            }
        }
        let mut lc = WheelLocalCompliance {
            diag,
            cross,
            cross2,
            axes,
            reference: [0.0; 3],
            phi_max: if span + 1 >= nt {
                f64::INFINITY
            } else {
                phi_max
            },
        };
        let at0 = super::locate_angle(thetas, 0.0);
        lc.reference = lc.g(at0).ok_or(ExplicitError::LocalComplianceMissing)?;
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

    /// The block from a unit load at plane `load` to the displacement at plane `read`
    /// (`[c][c']`: along `c'` under a load along `c`; planes at most two apart, by
    /// reciprocity for a read behind the load); `None` where not computed or farther apart.
    fn block(&self, read: i64, load: i64) -> Option<Block> {
        let nt = self.diag.len() as i64;
        let (r, l) = (read.rem_euclid(nt) as usize, load.rem_euclid(nt) as usize);
        let tr = |b: Block| -> Block { [0, 1, 2].map(|c| [0, 1, 2].map(|cp| b[cp][c])) };
        match read - load {
            0 => self.diag[l],
            1 => self.cross[l],
            2 => self.cross2[l],
            -1 => self.cross[r].map(tr),
            -2 => self.cross2[r].map(tr),
            _ => None,
        }
    }

    /// The static displacement (m, contact-frame components in the ground frame of the
    /// state at `load`) of the material point at `read` under the contact force `f` (N,
    /// contact frame) at `load`, with the wheel turned to `load`'s angle (the state in
    /// which the force acts there); `None` where the blocks were not computed.
    fn transfer(&self, read: OnWheel, load: OnWheel, f: [f64; 3]) -> Option<[f64; 3]> {
        let mut ground = [0.0; 3];
        for (e, fe) in f.iter().enumerate() {
            for c in 0..3 {
                ground[c] += fe * self.axes[e][c];
            }
        }
        let fr = super::to_spinning(load.cs, ground);
        let mut disp = [0.0; 3];
        for (i, wi) in [(read.j, 1.0 - read.s), (read.j + 1, read.s)] {
            for (j, wj) in [(load.j, 1.0 - load.s), (load.j + 1, load.s)] {
                if wi * wj == 0.0 {
                    continue;
                }
                let b = self.block(i, j)?;
                for c in 0..3 {
                    for cp in 0..3 {
                        disp[cp] += wi * wj * fr[c] * b[c][cp];
                    }
                }
            }
        }
        let g = super::to_ground(load.cs, disp);
        Some(self.axes.map(|a| a[0] * g[0] + a[1] * g[1] + a[2] * g[2]))
    }

    /// The convective part of the static deflection over a contact step (m, contact
    /// frame): the displacement increment of the material point at `new` when the force
    /// `f` (N, contact frame) held on the wheel moves from `old` to `new`,
    /// `L(new, new) f − L(new, old) f`. Zero on an axisymmetric wheel up to a constant; on
    /// the faceted tread it varies within each segment (docs/theory.md §8.7). `None` where
    /// the blocks were not computed.
    pub(super) fn convective(&self, new: OnWheel, old: OnWheel, f: [f64; 3]) -> Option<[f64; 3]> {
        let a = self.transfer(new, new, f)?;
        let b = self.transfer(new, old, f)?;
        Some([0, 1, 2].map(|d| a[d] - b[d]))
    }

    /// `g_d(φ) − g_d(0)` (m/N) with the contact at `at`; `None` where not computed.
    pub(super) fn variation(&self, at: OnWheel) -> Option<[f64; 3]> {
        let g = self.g(at)?;
        Some([0, 1, 2].map(|d| g[d] - self.reference[d]))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{locate_angle, to_spinning, PlaneNodes};
    use crate::explicit::{ExplicitModel, ExplicitOptions};
    use crate::model::{load_model, test_problems::SMALL_MODEL, ExplicitWheel, ModelSource};
    use crate::passage::contact_line::add_nodes_load;
    use crate::passage::free_body::{elastic_flexibility, FreeBody};
    use faer::Mat;

    /// The small model's rotating-wheel explicit model (local compliance removed).
    fn small_rotating() -> ExplicitModel {
        let sets: Vec<String> = SMALL_MODEL.iter().map(|s| s.to_string()).collect();
        let model = load_model(&ModelSource::Builtin, &sets).unwrap();
        let opts = ExplicitOptions {
            wheel: ExplicitWheel::Rotating,
            ..ExplicitOptions::default()
        };
        ExplicitModel::new(&model, opts).unwrap()
    }

    /// The small wheel's tread: its local compliance, free DOFs, angle planes, plane angles
    /// (rad), the contact plane's index and the contact frame's axes.
    struct Tread<'a> {
        lc: &'a super::WheelLocalCompliance,
        n: usize,
        planes: Vec<PlaneNodes>,
        th: &'a [f64],
        k0: usize,
        axes: [[f64; 3]; 3],
    }

    impl<'a> Tread<'a> {
        fn of(em: &'a ExplicitModel) -> Self {
            let w = &em.wheel_structure;
            let topo = &w.topology;
            Tread {
                lc: em.wheel_local.as_ref().unwrap(),
                n: w.dofmap.n_free(),
                planes: super::super::tread_planes(w, &em.wheel_nodes).unwrap(),
                th: &topo.thetas,
                k0: topo.contact_angle_index(),
                axes: [em.frame.x, em.frame.t, em.frame.n],
            }
        }
    }

    /// The independent inertia-relief flexibility `b_aᵀ G_e b_b` (m/N) between `loads` over
    /// the wheel body's mass (`elastic_flexibility`: its own statically determinate
    /// supports, Gram–Schmidt and factorisation; the sprung mass gets no inertial share).
    fn direct_flexibility(em: &ExplicitModel, loads: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let w = &em.wheel_structure;
        let (fm, _) = w.assemble().unwrap();
        let n = w.dofmap.n_free();
        let modes = Mat::from_fn(n, em.rigid.len(), |i, k| em.rigid[k][i]);
        let omega2 = vec![0.0; em.rigid.len()];
        let sprung: Vec<usize> = (0..3)
            .filter_map(|c| w.dofmap.free_index(3 * w.sprung_node + c))
            .collect();
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
        elastic_flexibility(body, loads).unwrap()
    }

    /// The tread load (or read) vector of `n` free DOFs at the material angle `phi` (rad),
    /// interpolated in angle between the planes at `th`, along the spinning-frame direction
    /// `ar`.
    fn angle_load(th: &[f64], planes: &[PlaneNodes], n: usize, phi: f64, ar: [f64; 3]) -> Vec<f64> {
        let at = locate_angle(th, phi);
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
        b
    }

    /// The tread compliance `g_d(φ)` at angle planes and between them against an independent
    /// inertia-relief solve ([`direct_flexibility`]) of the angle-interpolated load on the
    /// small wheel, to 1e-8 relative; the compliance with the variation removed is the
    /// reference at every angle, and the reference is the fixed wheel's compliance at its
    /// contact. The variation itself is not small (so the test can tell a removal from none).
    #[test]
    fn tread_compliance_matches_a_direct_inertia_relief_solve() {
        let em = small_rotating();
        let Tread {
            lc,
            n,
            planes,
            th,
            k0,
            axes,
        } = Tread::of(&em);
        // Plane angles and points between them, over the fine zone and the coarse segments.
        let mut phis = Vec::new();
        for k in [k0, k0 + 1, k0 + 2, k0 + 5, k0 + 8] {
            phis.push(th[k]);
            phis.push(th[k] + 0.37 * (th[k + 1] - th[k]));
        }
        let mut loads = Vec::new();
        for &phi in &phis {
            let cs = locate_angle(th, phi).cs;
            for ax in axes {
                loads.push(angle_load(th, &planes, n, phi, to_spinning(cs, ax)));
            }
        }
        // The fixed wheel's contact load.
        for d in 0..3 {
            let mut force = [0.0; 3];
            force[d] = 1.0;
            let mut b = vec![0.0; n];
            add_nodes_load(
                &em.wheel_nodes,
                &em.wheel_structure.dofmap,
                &em.frame,
                1.0,
                force,
                &mut b,
            );
            loads.push(b);
        }
        let direct = direct_flexibility(&em, &loads);
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

    /// The convective static deflection over a contact step from `φ₀` to `φ₁` against an
    /// independent inertia-relief solve ([`direct_flexibility`]) on the small wheel: the
    /// force `f` (contact frame) turned to the spinning frame at the load's angle, applied
    /// as the angle-interpolated tread load at `φ₁` and at `φ₀`, the displacement read at
    /// the material point of `φ₁` (same interpolation) and turned back to the contact frame
    /// at the load's angle. `transfer` at both loads and `convective` (their difference)
    /// agree with the direct solve to 1e-8 of the transferred displacement's size. Steps
    /// inside one coarse segment, across a plane (reading up to two planes past the load)
    /// and in the fine zone; the convective term is not small against the displacement (so
    /// the test can tell it from none).
    #[test]
    fn convective_deflection_matches_a_direct_inertia_relief_solve() {
        let em = small_rotating();
        let t = Tread::of(&em);
        let (lc, n, th, k0, axes) = (t.lc, t.n, t.th, t.k0, t.axes);
        let planes = t.planes;
        let at_frac = |k: usize, s: f64| th[k] + s * (th[k + 1] - th[k]);
        // (φ₀, φ₁): in one coarse segment, across a plane (twice: the second reads two planes
        // past the load), in the fine zone.
        let steps = [
            (at_frac(k0 + 5, 0.2), at_frac(k0 + 5, 0.7)),
            (at_frac(k0 + 6, 0.8), at_frac(k0 + 7, 0.3)),
            (at_frac(k0 + 4, 0.6), at_frac(k0 + 5, 0.1)),
            (at_frac(k0, 0.1), at_frac(k0, 0.45)),
        ];
        let f = [2.5e3, -1.2e3, 7.0e4];
        let mut largest: f64 = 0.0;
        for (phi0, phi1) in steps {
            let (new, old) = (locate_angle(th, phi1), locate_angle(th, phi0));
            // Loads at φ₁ and φ₀ along each contact direction turned at the load's angle,
            // reads at φ₁ along each contact direction turned at φ₁ and at φ₀.
            let mut loads = Vec::new();
            for (phi_pt, cs) in [(phi1, new.cs), (phi0, old.cs), (phi1, old.cs)] {
                for ax in axes {
                    loads.push(angle_load(th, &planes, n, phi_pt, to_spinning(cs, ax)));
                }
            }
            let g = direct_flexibility(&em, &loads);
            // Displacement along e: Σ_d f_d (read e)ᵀ G (load d).
            let direct = |read: usize, load: usize| -> [f64; 3] {
                [0, 1, 2].map(|e| (0..3).map(|d| f[d] * g[read + e][load + d]).sum())
            };
            let (a, b) = (direct(0, 0), direct(6, 3));
            let scale = a.iter().chain(&b).fold(0.0_f64, |m, x| m.max(x.abs()));
            let ta = lc.transfer(new, new, f).unwrap();
            let tb = lc.transfer(new, old, f).unwrap();
            let conv = lc.convective(new, old, f).unwrap();
            for e in 0..3 {
                let want = a[e] - b[e];
                for (got, exp, what) in [(ta[e], a[e], "at φ₁"), (tb[e], b[e], "from φ₀")] {
                    assert!(
                        (got - exp).abs() <= 1e-8 * scale,
                        "φ₀ {phi0} φ₁ {phi1} e {e}: transfer {what} {got} vs direct {exp}"
                    );
                }
                assert!(
                    (conv[e] - want).abs() <= 1e-8 * scale,
                    "φ₀ {phi0} φ₁ {phi1} e {e}: convective {} vs direct {want}",
                    conv[e]
                );
                largest = largest.max(want.abs() / scale);
            }
        }
        eprintln!("convective deflection: largest {largest:.3e} of the displacement");
        assert!(
            largest > 1e-3,
            "convective term only {largest} of the displacement"
        );
    }
}
