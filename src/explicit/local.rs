//! The mesh's local compliance under the moving contact load, and its removal from the
//! contact (docs/theory.md §8.6).
//!
//! Under a load spread over the patch with the plane weights `w(x)`, the rail's static
//! displacement at the load, per unit load in contact-frame direction `d`, is the quadratic
//! form `g_d(x) = Σ_jk w_j(x) w_k(x) b_{k,d}ᵀ K⁻¹ b_{j,d}` (m/N), `b_{j,d}` the unit load of
//! node plane `j`. On a finite-element mesh `g_d` varies with the load's position inside
//! each element: a discretisation artefact, since the continuum's local compliance is the
//! same everywhere and the contact model's half-space already holds it. The explicit path
//! therefore gives the contact the compliance variation back with the opposite sign, as a
//! series compliance `−Δg_d(x)`, where `Δg_d(x) = g_d(x) − ḡ_d(x)` and `ḡ_d` is the mean of
//! `g_d` over each element, interpolated linearly between element centres (it keeps the
//! physical variation at the sleeper pitch). The local deformation is quasi-static (its
//! frequencies, of order 100 kHz on a 10 mm mesh, are far above the band), so the static
//! `Δg` is the right correction. The reduced passage's mean residual flexibility (§7.7) is
//! constant along the rail in the same sense.

use super::ExplicitError;
use crate::passage::contact_line::{ContactFrame, RailContactLine};
use crate::passage::planes::{max_planes, plane_weights, PlaneWeights};
use crate::passage::statics::{for_each_plane_solution, nodes_dot, StiffnessFactor};
use crate::structure::TrackStructure;

/// Sub-intervals per element of the element means of `g`.
const SUB: usize = 4;

/// Four-point Gauss–Legendre rule on [−1, 1] (per sub-interval of the element means).
const GAUSS4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// The static plane-to-plane compliances of the rail's contact line over a stretch, and the
/// element means of the patch compliance `g_d(x)`.
pub(super) struct LocalCompliance {
    /// First plane covered.
    p0: usize,
    /// Planes covered.
    np: usize,
    /// Half-width of the stored band of plane pairs (planes).
    half: usize,
    /// `c[(j − p0)·(2·half + 1) + (k + half − j)][d] = b_{k,d}ᵀ K⁻¹ b_{j,d}` (m/N).
    c: Vec<[f64; 3]>,
    /// Centres of the elements covered (m) and the mean of `g_d` over each (m/N).
    centres_m: Vec<f64>,
    means: Vec<[f64; 3]>,
    /// Patch half-length (m).
    a_m: f64,
}

impl LocalCompliance {
    /// Computes the compliances for a contact travelling over `[x_lo, x_hi]` (m) with the
    /// patch half-length `a_m` (m): one block solve of the factorised `K` per covered plane
    /// and direction.
    pub(super) fn compute(
        track: &TrackStructure,
        factor: &StiffnessFactor,
        line: &RailContactLine,
        frame: &ContactFrame,
        a_m: f64,
        [x_lo, x_hi]: [f64; 2],
    ) -> Result<Self, ExplicitError> {
        let px = &line.planes_x_m;
        let first = plane_weights(px, x_lo, a_m)?;
        let last = plane_weights(px, x_hi, a_m)?;
        let (p0, p1) = (first.first, last.last());
        let np = p1 - p0 + 1;
        let half = max_planes(px, a_m);
        let width = 2 * half + 1;
        let mut c = vec![[0.0; 3]; np * width];
        let axes = [frame.x, frame.t, frame.n];
        let dm = &track.dofmap;
        for_each_plane_solution(track, factor, line, frame, p0, p1, &mut |i, d, u| {
            let j = p0 + i;
            for k in j.saturating_sub(half).max(p0)..=(j + half).min(p1) {
                c[i * width + (k + half - j)][d] = nodes_dot(&line.nodes[k], dm, axes[d], u);
            }
        });
        let mut lc = LocalCompliance {
            p0,
            np,
            half,
            c,
            centres_m: Vec::new(),
            means: Vec::new(),
            a_m,
        };
        lc.element_means(px, x_lo, x_hi)?;
        Ok(lc)
    }

    /// The element means of `g` for the elements whose centres lie in `[x_lo, x_hi]` (m).
    fn element_means(&mut self, px: &[f64], x_lo: f64, x_hi: f64) -> Result<(), ExplicitError> {
        for e in 0..px.len() - 1 {
            let (xa, xb) = (px[e], px[e + 1]);
            let xm = 0.5 * (xa + xb);
            if xm < x_lo || xm > x_hi {
                continue;
            }
            // Composite rule: SUB sub-intervals of four Gauss points (g has kinks where a
            // patch end crosses a plane).
            let mut mean = [0.0; 3];
            let h = (xb - xa) / SUB as f64;
            for k in 0..SUB {
                let c = xa + (k as f64 + 0.5) * h;
                for (g, gw) in GAUSS4 {
                    let x = c + 0.5 * h * g;
                    let w = plane_weights(px, x.clamp(x_lo, x_hi), self.a_m)?;
                    let gx = self.g(&w);
                    for d in 0..3 {
                        mean[d] += 0.5 * gw * gx[d] / SUB as f64;
                    }
                }
            }
            self.centres_m.push(xm);
            self.means.push(mean);
        }
        Ok(())
    }

    /// The static compliance `g_d` under the patch of plane weights `w` (m/N); planes outside
    /// the covered stretch contribute nothing.
    pub(super) fn g(&self, w: &PlaneWeights) -> [f64; 3] {
        let width = 2 * self.half + 1;
        let mut g = [0.0; 3];
        for (j, wj) in w.iter() {
            if j < self.p0 || j >= self.p0 + self.np {
                continue;
            }
            for (k, wk) in w.iter() {
                if k + self.half < j || k > j + self.half {
                    continue;
                }
                let c = &self.c[(j - self.p0) * width + (k + self.half - j)];
                for d in 0..3 {
                    g[d] += wj * wk * c[d];
                }
            }
        }
        g
    }

    /// `Δg_d(x) = g_d(x) − ḡ_d(x)` (m/N) with the contact at `x` (m) and its plane weights
    /// `w`; zero outside the covered stretch.
    pub(super) fn variation(&self, x: f64, w: &PlaneWeights) -> [f64; 3] {
        let cs = &self.centres_m;
        if cs.is_empty()
            || w.first < self.p0
            || w.last() >= self.p0 + self.np
            || x < cs[0]
            || x > cs[cs.len() - 1]
        {
            return [0.0; 3];
        }
        let i = cs.partition_point(|&c| c <= x).clamp(1, cs.len() - 1) - 1;
        let s = if cs[i + 1] > cs[i] {
            ((x - cs[i]) / (cs[i + 1] - cs[i])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let g = self.g(w);
        [0, 1, 2].map(|d| g[d] - ((1.0 - s) * self.means[i][d] + s * self.means[i + 1][d]))
    }
}

#[cfg(test)]
mod tests {
    use super::{
        nodes_dot, plane_weights, ContactFrame, LocalCompliance, RailContactLine, StiffnessFactor,
        TrackStructure,
    };
    use crate::model::{load_model, ModelSource};
    use crate::passage::contact_line::add_nodes_load;
    use faer::Mat;

    /// The small test track with 40 mm elements along the rail.
    fn small() -> (TrackStructure, crate::fe::assembly::FeMatrices) {
        let o: Vec<String> = [
            "track.bays=4",
            "mesh.element_length=0.04",
            "mesh.fine_element_length=0.04",
            "mesh.section_size=0.03",
            "mesh.head_size=0.015",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let m = load_model(&ModelSource::Builtin, &o).unwrap();
        let t = TrackStructure::build(&m).unwrap();
        let (mats, _) = t.assemble().unwrap();
        (t, mats)
    }

    #[test]
    fn patch_compliance_matches_a_direct_solve_and_its_element_means_integrate_it() {
        let (t, mats) = small();
        let frame = ContactFrame::for_inclination(0.025);
        let n = t.dofmap.n_free();
        let line = RailContactLine::new(&t, &Mat::zeros(n, 0), &frame, 0.005).unwrap();
        let fac = StiffnessFactor::new(mats.k.as_ref()).unwrap();
        let axes = [frame.x, frame.t, frame.n];
        for a in [0.007, 0.05] {
            let range = [0.9, 1.3];
            let lc = LocalCompliance::compute(&t, &fac, &line, &frame, a, range).unwrap();
            // Independent: assemble the spread unit load, solve K u = b, read bᵀu.
            for x in [0.93, 1.013, 1.1, 1.2777] {
                let w = plane_weights(&line.planes_x_m, x, a).unwrap();
                let g = lc.g(&w);
                for d in 0..3 {
                    let mut force = [0.0; 3];
                    force[d] = 1.0;
                    let mut b = vec![0.0; n];
                    for (j, wj) in w.iter() {
                        add_nodes_load(&line.nodes[j], &t.dofmap, &frame, wj, force, &mut b);
                    }
                    let u = super::super::start::solve_one(&fac, &b);
                    let direct: f64 = w
                        .iter()
                        .map(|(j, wj)| wj * nodes_dot(&line.nodes[j], &t.dofmap, axes[d], |i| u[i]))
                        .sum();
                    assert!(
                        (g[d] - direct).abs() <= 1e-9 * direct.abs(),
                        "a {a} x {x} d {d}: {} vs {direct}",
                        g[d]
                    );
                }
            }
            // Element means against a fine midpoint rule of g over each element.
            let px = &line.planes_x_m;
            for (e, &xm) in lc.centres_m.iter().enumerate() {
                let i = px.partition_point(|&v| v <= xm) - 1;
                let (xa, xb) = (px[i], px[i + 1]);
                let k = 400;
                let mut mean = [0.0; 3];
                for s in 0..k {
                    let x =
                        (xa + (s as f64 + 0.5) / k as f64 * (xb - xa)).clamp(range[0], range[1]);
                    let g = lc.g(&plane_weights(px, x, a).unwrap());
                    for d in 0..3 {
                        mean[d] += g[d] / k as f64;
                    }
                }
                for d in 0..3 {
                    let rel = (lc.means[e][d] - mean[d]).abs() / mean[d].abs();
                    assert!(rel < 1e-3, "a {a} element {e} d {d}: {rel:e}");
                }
            }
            // The variation vanishes off the covered stretch.
            let w = plane_weights(px, 0.5, a).unwrap();
            assert_eq!(lc.variation(0.5, &w), [0.0; 3]);
        }
    }
}
