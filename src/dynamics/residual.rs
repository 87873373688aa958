//! Residual (static) flexibility of the rail at the moving contact (docs/theory.md §7.7).
//!
//! # What it is
//! For a unit force in direction `d` of the contact frame (x rolling, t lateral tangent,
//! n normal) spread over the contact nodes of node plane `p` with the **same** lateral
//! weights as the passage's modal rows ([`RailContactLine`]), the load vector is `b_{p,d}`
//! (free DOFs). Its static flexibility splits into the part the kept modes carry and the
//! truncated remainder (Craig & Kurdila, *Fundamentals of Structural Dynamics*, 2006, §14.4):
//!
//! ```text
//! G_d(p)  = b_{p,d}ᵀ K⁻¹ b_{p,d}                       full FE (sparse LLᵀ of K, once)
//! M_d(p)  = Σ_k r_{d,k}(x_p)² / ω_k²                   modal (kept modes, r = Φᵀ b)
//! R_d(p)  = G_d(p) − M_d(p) ≥ 0                        residual flexibility (m/N)
//! ```
//!
//! `R ≥ 0` by the Rayleigh–Ritz bound. The modes above f_max respond quasi-statically to
//! the contact force (their frequencies are far above the excitation), so the rail
//! displacement at the contact is `u_d = r_d · q + R_d F_d`: the truncated modes act as a
//! massless spring in series with the contact (the "static correction").
//!
//! # Between node planes
//! The passage interpolates the modal rows linearly between the two planes around `x_c`
//! (the hexahedron's shape function), so its load at `x_c` is
//! `b(x_c) = (1−s) b_p + s b_{p+1}`. The flexibility of *that* load is the quadratic form
//! `(1−s)² G_pp + 2s(1−s) G_{p,p+1} + s² G_{p+1,p+1}` ([`ResidualFlexibility::consistent_at`]):
//! it dips between planes because a load shared by two planes indents the mesh less. The
//! linear interpolation of the plane values ([`ResidualFlexibility::at`]) exceeds it by
//! `s(1−s)(R_pp + R_{p+1,p+1} − 2R_{p,p+1})`; measured at mid-element
//! ([`ResidualFlexibility::interpolation_excess`]): +94 % in x, +90 % in n on the default
//! model at 5 kHz (20 mm elements), +134 % / +96 % on the test track at 3 kHz (80 mm) —
//! the plane value is dominated by local indentation under a load concentrated on one node
//! plane, and the consistent form would modulate the contact stiffness at the
//! element-passing wavelength (inside the 20–80 mm band for 20 mm elements; the default
//! zone elements are 10 mm, docs/theory.md §3.1).
//!
//! # Local contact flexibility (docs/theory.md §7.7, "do not count it twice")
//! `G` of a Hertz-sized load on the mesh contains local indentation of the head that the
//! contact's half-space already supplies (Hertz `dδ/dF` = 6.9e-10 m/N at 100 kN; Mindlin's
//! no-slip tangential compliance ≈ 8.4e-10 m/N). Measured ([`lateral_spread_flexibility`],
//! tests/moving_load.rs `residual_flexibility_report`, default model, 126 800 DOFs, 2 kHz,
//! m/N): G_x 1.22e-9 (modal 2.8e-10), G_n 9.86e-9 (modal 9.07e-9). Spreading the same load
//! across the head over 2×, 3×, 5× the Hertz semi-width lowers G_x to 8.1e-10, 7.4e-10,
//! 6.6e-10 and G_n to 9.52e-9, 9.47e-9, 9.41e-9: about half of the plane residual in x and
//! n is local. The residual of the load spread over one element (the mid-element value,
//! [`ResidualFlexibility::mid_element`]) at 1/2/3/5 kHz: x 6.1/5.6/4.7/4.2e-10, n
//! 8.0/4.9/4.1/3.5e-10, t 1.9e-9/9.4/6.4/4.3e-10; on the test track at 3 kHz it agrees with
//! the laterally spread estimate (x 2.7e-10 both, n 2.2e-10 both), on the default mesh the
//! lateral spread gives about 30 % less (x 3.8e-10, n 3.5e-10 at 2 kHz), so it may still
//! hold some local part.
//!
//! **Decision.** The passage corrects **x, t and n** with the structural (mid-element)
//! residual ([`ResidualFlexibility::mid_element`]), as one constant per direction: its
//! length-weighted mean along the travel ([`ResidualFlexibility::mean_structural_weighted`];
//! why constant is said there). In x it is 2× the modal flexibility itself (the truncated
//! basis makes the rail head far too stiff longitudinally: web and foot shear above f_max
//! with the foot held at the RPM3 strips), in n it is 5 % of the rail's flexibility but
//! 50–70 % of the Hertz compliance at 2–5 kHz, and neither depends on the lateral spread of
//! the load — so it is structural and is not in the half-space. The plane value is not used
//! (local indentation counted twice, and mesh-dependent). Effect on a passage (default
//! model, `run.fmax = 2000`, 140 km/h, smooth rail, 2 cores): F_L band RMS 15.6 N without the
//! correction, 8.8 N with it; F_N band RMS 77.1 → 37.7 N; dominant wear wavelength 27.6 →
//! 36.5 mm (the ≈ 1.4 kHz F_L component weakens, the ≈ 1.07 kHz one stays); mean F_N and
//! F_L unchanged within 0.05 %. Energy balance of the small model of tests/passage.rs with
//! the residual spring counted: within 0.1 %.
use faer::sparse::SparseColMat;
use faer::Mat;
use serde::{Deserialize, Serialize};

use super::reduced::{ContactFrame, RailContactLine};
use super::DynamicsError;
pub use crate::passage::statics::{
    for_each_plane_solution, nodes_dot, plane_range, SharedStiffnessAnalysis, StiffnessFactor,
};
use crate::structure::TrackStructure;

use crate::passage::statics::BLOCK;

/// Revision of the cached residual-flexibility format / method; part of the cache name.
pub(crate) const RESIDUAL_REVISION: u64 = 1;

/// Residual flexibility along the contact line, per node plane, for the three contact-frame
/// directions `[x, t, n]` (m/N).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualFlexibility {
    /// Index of the first plane covered in the contact line (−).
    pub first_plane: usize,
    /// Positions of the covered planes (m), ascending.
    pub planes_x_m: Vec<f64>,
    /// Full static FE flexibility `b_dᵀ K⁻¹ b_d` per plane, `[x, t, n]` (m/N).
    pub static_m_per_n: Vec<[f64; 3]>,
    /// Modal part `Σ r_d² / ω²` per plane (m/N).
    pub modal_m_per_n: Vec<[f64; 3]>,
    /// Residual cross flexibility between plane `i` and `i+1`,
    /// `b_{i,d}ᵀ K⁻¹ b_{i+1,d} − Σ r_{i,d} r_{i+1,d} / ω²` (m/N), one fewer than planes.
    pub cross_residual_m_per_n: Vec<[f64; 3]>,
    /// Number of kept modes (−).
    pub modes: usize,
}

/// `G_d(p)` for the planes `p0..=p1` and the cross terms `b_{p,d}ᵀ K⁻¹ b_{p+1,d}`, for the
/// contact nodes and weights of `line` (the line's modes are not used): each as the dot
/// product of whitened loads ([`StiffnessFactor::whiten_in_place`]), in blocks of planes,
/// the last plane of a block kept for the next block's first cross term.
fn static_flexibility(
    track: &TrackStructure,
    factor: &StiffnessFactor,
    line: &RailContactLine,
    frame: &ContactFrame,
    p0: usize,
    p1: usize,
) -> Result<PlaneFlexibility, DynamicsError> {
    let np = p1 - p0 + 1;
    let n = factor.n();
    let per_block = (BLOCK / 3).max(1);
    let mut g = vec![[0.0; 3]; np];
    let mut cross = vec![[0.0; 3]; np.saturating_sub(1)];
    let mut z = Mat::<f64>::zeros(n, 3 * per_block.min(np));
    let mut prev = Mat::<f64>::zeros(n, 3);
    let mut b = vec![0.0; n];
    let dot = |a: faer::ColRef<'_, f64>, c: faer::ColRef<'_, f64>| -> f64 {
        a.iter().zip(c.iter()).map(|(x, y)| x * y).sum()
    };
    let mut first = 0;
    while first < np {
        let planes = per_block.min(np - first);
        let mut block = z.as_mut().subcols_mut(0, 3 * planes);
        for i in 0..planes {
            for d in 0..3 {
                let mut force = [0.0; 3];
                force[d] = 1.0;
                b.iter_mut().for_each(|v| *v = 0.0);
                super::reduced::add_nodes_load(
                    &line.nodes[p0 + first + i],
                    &track.dofmap,
                    frame,
                    1.0,
                    force,
                    &mut b,
                );
                block
                    .as_mut()
                    .col_mut(3 * i + d)
                    .iter_mut()
                    .zip(&b)
                    .for_each(|(o, &v)| *o = v);
            }
        }
        factor.whiten_in_place(block.as_mut())?;
        for i in 0..planes {
            for d in 0..3 {
                let c = block.as_ref().col(3 * i + d);
                g[first + i][d] = dot(c, c);
                if i > 0 {
                    cross[first + i - 1][d] = dot(block.as_ref().col(3 * (i - 1) + d), c);
                } else if first > 0 {
                    cross[first - 1][d] = dot(prev.col(d), c);
                }
            }
        }
        for d in 0..3 {
            prev.col_mut(d)
                .copy_from(block.as_ref().col(3 * (planes - 1) + d));
        }
        first += planes;
    }
    Ok((g, cross))
}

/// Per node plane `[x, t, n]` values (m/N): `G` of each plane and the cross terms of each
/// plane with the next.
pub type PlaneFlexibility = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// The static flexibility of the track at its contact line: `G_d(p) = b_{p,d}ᵀ K⁻¹ b_{p,d}`
/// per node plane `p` of `p0..=p1` and direction `d` of the contact frame, and the cross
/// terms `b_{p,d}ᵀ K⁻¹ b_{p+1,d}` (m/N), for the unit contact loads of
/// [`for_each_plane_solution`]. [`StiffnessFactor`] solves with the factorised `K`; a
/// design study may instead update a reference factorisation for changed spring
/// stiffnesses (`crate::studies::study`).
pub trait StaticFlexibility {
    /// Rows of `K` (the track's free DOFs).
    fn n(&self) -> usize;
    /// `(G, cross)` for the planes `p0..=p1` of `line` (`p1 − p0` cross terms).
    fn plane_flexibility(
        &self,
        track: &TrackStructure,
        line: &RailContactLine,
        frame: &ContactFrame,
        p0: usize,
        p1: usize,
    ) -> Result<PlaneFlexibility, DynamicsError>;
}

impl StaticFlexibility for StiffnessFactor {
    fn n(&self) -> usize {
        StiffnessFactor::n(self)
    }

    fn plane_flexibility(
        &self,
        track: &TrackStructure,
        line: &RailContactLine,
        frame: &ContactFrame,
        p0: usize,
        p1: usize,
    ) -> Result<PlaneFlexibility, DynamicsError> {
        static_flexibility(track, self, line, frame, p0, p1)
    }
}

/// The kept track modes as the residual flexibility sees them: their rows on the rail's
/// contact line, the contact frame, and their squared frequencies (rad²/s², all > 0: the
/// track is supported).
#[derive(Clone, Copy)]
pub struct LineModes<'a> {
    /// The contact line built from the kept modes.
    pub line: &'a RailContactLine,
    /// The contact frame (x, t, n).
    pub frame: &'a ContactFrame,
    /// The modes' squared angular frequencies (rad²/s²).
    pub omega2: &'a [f64],
}

impl ResidualFlexibility {
    /// Computes the residual flexibility of the planes a contact travelling over
    /// `x_range_m` (m, either order) uses, for the kept modes `lm`; `factor` gives the static
    /// flexibility (e.g. the factorised `K`, [`StiffnessFactor`]).
    pub fn compute(
        track: &TrackStructure,
        factor: &dyn StaticFlexibility,
        lm: LineModes<'_>,
        x_range_m: [f64; 2],
    ) -> Result<Self, DynamicsError> {
        let LineModes {
            line,
            frame,
            omega2,
        } = lm;
        let [x_lo, x_hi] = x_range_m;
        let m = line.modes;
        if omega2.len() != m {
            return Err(DynamicsError::SizeMismatch {
                what: "residual flexibility: frequencies vs modes of the contact line (build both from the same basis)",
                found: omega2.len(),
                expected: m,
            });
        }
        if let Some(i) = omega2.iter().position(|&w| w.is_nan() || w <= 0.0) {
            return Err(DynamicsError::TrackNotSupported {
                mode: i,
                omega2_rad2_s2: omega2[i],
            });
        }
        if factor.n() != track.dofmap.n_free() {
            return Err(DynamicsError::SizeMismatch {
                what: "residual flexibility: rows of K vs free DOFs of the track",
                found: factor.n(),
                expected: track.dofmap.n_free(),
            });
        }
        let (p0, p1) = plane_range(line, x_lo.min(x_hi), x_lo.max(x_hi))?;
        let (g, gc) = factor.plane_flexibility(track, line, frame, p0, p1)?;
        if g.len() != p1 - p0 + 1 || gc.len() != p1 - p0 {
            return Err(DynamicsError::SizeMismatch {
                what: "residual flexibility: static flexibility values vs node planes",
                found: g.len() + gc.len(),
                expected: 2 * (p1 - p0) + 1,
            });
        }
        let np = p1 - p0 + 1;
        let mut rows: Vec<Vec<f64>> = Vec::with_capacity(np);
        for p in p0..=p1 {
            let mut r = vec![0.0; 3 * m];
            line.rows_at(line.planes_x_m[p], &mut r)?;
            rows.push(r);
        }
        let modal_of = |a: &[f64], b: &[f64], d: usize| -> f64 {
            (0..m)
                .map(|k| a[d * m + k] * b[d * m + k] / omega2[k])
                .sum()
        };
        let modal: Vec<[f64; 3]> = rows
            .iter()
            .map(|r| [modal_of(r, r, 0), modal_of(r, r, 1), modal_of(r, r, 2)])
            .collect();
        let cross: Vec<[f64; 3]> = (0..np.saturating_sub(1))
            .map(|i| {
                let (a, b) = (&rows[i], &rows[i + 1]);
                [
                    gc[i][0] - modal_of(a, b, 0),
                    gc[i][1] - modal_of(a, b, 1),
                    gc[i][2] - modal_of(a, b, 2),
                ]
            })
            .collect();
        let out = ResidualFlexibility {
            first_plane: p0,
            planes_x_m: line.planes_x_m[p0..=p1].to_vec(),
            static_m_per_n: g,
            modal_m_per_n: modal,
            cross_residual_m_per_n: cross,
            modes: m,
        };
        out.check()?;
        Ok(out)
    }

    /// Consistency and the Rayleigh–Ritz bound `R ≥ 0` (to round-off: 1e-9 of G).
    fn check(&self) -> Result<(), DynamicsError> {
        let np = self.planes_x_m.len();
        if np < 2
            || self.static_m_per_n.len() != np
            || self.modal_m_per_n.len() != np
            || self.cross_residual_m_per_n.len() != np - 1
            || self
                .planes_x_m
                .windows(2)
                .any(|w| w[1].is_nan() || w[1] <= w[0])
        {
            return Err(DynamicsError::ResidualPlanes);
        }
        for (p, (g, md)) in self
            .static_m_per_n
            .iter()
            .zip(&self.modal_m_per_n)
            .enumerate()
        {
            for d in 0..3 {
                if !(g[d].is_finite() && md[d].is_finite()) || g[d] - md[d] < -1e-9 * g[d].abs() {
                    return Err(DynamicsError::ResidualBelowModal {
                        x_m: self.planes_x_m[p],
                        direction: d,
                        fe_m_per_n: g[d],
                        modal_m_per_n: md[d],
                    });
                }
            }
        }
        Ok(())
    }

    /// Residual flexibility `R_d = G_d − M_d` of covered plane `i` (m/N), clamped at 0.
    pub fn residual(&self, i: usize) -> [f64; 3] {
        let (g, m) = (self.static_m_per_n[i], self.modal_m_per_n[i]);
        [
            (g[0] - m[0]).max(0.0),
            (g[1] - m[1]).max(0.0),
            (g[2] - m[2]).max(0.0),
        ]
    }

    fn locate(&self, x: f64) -> Option<(usize, f64)> {
        let px = &self.planes_x_m;
        if !(x >= px[0] && x <= px[px.len() - 1]) {
            return None;
        }
        let p = px.partition_point(|&v| v <= x).clamp(1, px.len() - 1) - 1;
        Some((p, (x - px[p]) / (px[p + 1] - px[p])))
    }

    fn off(&self, x: f64) -> DynamicsError {
        DynamicsError::OutsideResidual {
            x_m: x,
            start_m: self.planes_x_m[0],
            end_m: self.planes_x_m[self.planes_x_m.len() - 1],
        }
    }

    /// True when `[x_lo, x_hi]` (m) lies in the covered planes.
    pub fn covers(&self, x_lo: f64, x_hi: f64) -> bool {
        self.locate(x_lo).is_some() && self.locate(x_hi).is_some()
    }

    /// `R(x)` (m/N, `[x, t, n]`): linear interpolation of the plane values (what the passage
    /// uses; see the module doc). No allocation.
    pub fn at(&self, x: f64) -> Result<[f64; 3], DynamicsError> {
        let (p, s) = self.locate(x).ok_or_else(|| self.off(x))?;
        let (a, b) = (self.residual(p), self.residual(p + 1));
        Ok([0, 1, 2].map(|d| (1.0 - s) * a[d] + s * b[d]))
    }

    /// `R(x)` of the load the passage applies at `x` (both planes' shape functions):
    /// `(1−s)² R_pp + 2s(1−s) R_{p,p+1} + s² R_{p+1,p+1}` (m/N).
    pub fn consistent_at(&self, x: f64) -> Result<[f64; 3], DynamicsError> {
        let (p, s) = self.locate(x).ok_or_else(|| self.off(x))?;
        let (a, b, c) = (
            self.residual(p),
            self.residual(p + 1),
            self.cross_residual_m_per_n[p],
        );
        Ok([0, 1, 2].map(|d| {
            ((1.0 - s).powi(2) * a[d] + 2.0 * s * (1.0 - s) * c[d] + s * s * b[d]).max(0.0)
        }))
    }

    /// Residual of the load shared equally by the two planes of interval `i` (the
    /// consistent form at mid-element), `¼(R_ii + R_{i+1,i+1} + 2R_{i,i+1})` (m/N).
    pub fn mid_element(&self, i: usize) -> [f64; 3] {
        let (a, b, c) = (
            self.residual(i),
            self.residual(i + 1),
            self.cross_residual_m_per_n[i],
        );
        [0, 1, 2].map(|d| (0.25 * (a[d] + b[d] + 2.0 * c[d])).max(0.0))
    }

    /// Largest relative excess of the linear interpolation over the consistent form,
    /// `(at − consistent)/consistent` at mid-element, per direction (−).
    pub fn interpolation_excess(&self) -> [f64; 3] {
        let mut worst = [0.0f64; 3];
        for w in self.planes_x_m.windows(2) {
            let x = 0.5 * (w[0] + w[1]);
            if let (Ok(l), Ok(c)) = (self.at(x), self.consistent_at(x)) {
                for d in 0..3 {
                    if c[d] > 0.0 {
                        worst[d] = worst[d].max(l[d] / c[d] - 1.0);
                    }
                }
            }
        }
        worst
    }

    /// Length-weighted mean of the structural (mid-element) residual over the covered
    /// intervals (m/N, `[x, t, n]`): the constant series compliance the passage applies.
    ///
    /// Why constant: on a non-uniform mesh (e.g. RPM1, whose three held column strips add
    /// node planes, 9–19 mm elements) the mid-element value changes by a few % from one
    /// element to the next with the element length — a mesh artefact that, applied along
    /// x, modulates the contact stiffness at element-scale wavelengths inside or near the
    /// 20–80 mm band (measured on RPM1 at 140 km/h: F_N band RMS 58 N without the
    /// correction, 490 N with the position-dependent value). The physical variation of the
    /// truncated-mode flexibility with the sleeper position is at the sleeper pitch (0.6 m),
    /// outside the band, and the kept modes carry the track's own variation.
    pub fn mean_structural_weighted(&self) -> [f64; 3] {
        let mut out = [0.0; 3];
        let mut len = 0.0;
        for i in 0..self.cross_residual_m_per_n.len() {
            let w = self.planes_x_m[i + 1] - self.planes_x_m[i];
            let r = self.mid_element(i);
            for d in 0..3 {
                out[d] += w * r[d];
            }
            len += w;
        }
        if len > 0.0 {
            out.map(|v| v / len)
        } else {
            out
        }
    }

    /// Mean over the covered planes of `(G, modal, R)` per direction (m/N), for reports.
    pub fn means(&self) -> [[f64; 3]; 3] {
        let np = self.planes_x_m.len() as f64;
        let mut out = [[0.0; 3]; 3];
        for i in 0..self.planes_x_m.len() {
            let r = self.residual(i);
            for d in 0..3 {
                out[0][d] += self.static_m_per_n[i][d] / np;
                out[1][d] += self.modal_m_per_n[i][d] / np;
                out[2][d] += r[d] / np;
            }
        }
        out
    }
}

/// The static FE flexibility `b_dᵀ K⁻¹ b_d` (m/N, `[x, t, n]`) of plane `plane` for the
/// contact load spread across the head with the Hertz-like weights of semi-width
/// `half_width_m` (m) — for measuring how much of `G` is local indentation (it shrinks as
/// the load spreads) and how much structural (it does not).
pub fn lateral_spread_flexibility(
    track: &TrackStructure,
    factor: &StiffnessFactor,
    frame: &ContactFrame,
    half_width_m: f64,
    plane: usize,
) -> Result<[f64; 3], DynamicsError> {
    // The line's modal rows are not needed: an empty basis.
    let empty = Mat::<f64>::zeros(track.dofmap.n_free(), 0);
    let line = RailContactLine::new(track, &empty, frame, half_width_m)?;
    if plane + 1 >= line.planes_x_m.len() {
        return Err(DynamicsError::PlaneOutOfRange {
            plane,
            planes: line.planes_x_m.len(),
        });
    }
    let (g, _) = static_flexibility(track, factor, &line, frame, plane, plane + 1)?;
    Ok(g[0])
}

/// Loads the residual flexibility of the track basis under `key` from the modal cache, or
/// computes it (factorising `K` once, assembled by `k` only then) and stores it there, next to
/// the modes. The file's name holds what else determines it (the lateral weights'
/// semi-width and the contact frame's normal).
pub(crate) fn cached_residual(
    cache: &crate::eigen::cache::ModalCache,
    key: &crate::eigen::cache::CacheKey,
    track: &TrackStructure,
    k: &dyn Fn() -> Result<SparseColMat<usize, f64>, DynamicsError>,
    lm: LineModes<'_>,
    half_width_m: f64,
    x_range_m: [f64; 2],
) -> Result<(ResidualFlexibility, bool), DynamicsError> {
    let (line, frame) = (lm.line, lm.frame);
    let name = format!(
        "residual-r{RESIDUAL_REVISION}-b{:016x}-n{}.json",
        half_width_m.to_bits(),
        frame.n[1].to_bits()
    );
    if let Some(bytes) = cache.load_aux(key, &name) {
        if let Ok(r) = serde_json::from_slice::<ResidualFlexibility>(&bytes) {
            if r.modes == line.modes
                && r.check().is_ok()
                && r.covers(x_range_m[0], x_range_m[1])
                && r.first_plane + r.planes_x_m.len() <= line.planes_x_m.len()
            {
                return Ok((r, true));
            }
        }
    }
    let factor = StiffnessFactor::new(k()?.as_ref())?;
    let r = ResidualFlexibility::compute(track, &factor, lm, x_range_m)?;
    let bytes = serde_json::to_vec(&r)?;
    if let Err(e) = cache.store_aux(key, &name, &bytes) {
        cache
            .progress()
            .warn(&format!("could not cache the residual flexibility: {e}"));
    }
    // Use the values exactly as a cache hit reads them back (serde_json may parse one ulp
    // off), so a fresh and a cached run give identical results.
    let r = serde_json::from_slice(&bytes)?;
    Ok((r, false))
}

#[cfg(test)]
mod tests {
    use super::{
        for_each_plane_solution, nodes_dot, static_flexibility, ContactFrame, Mat, RailContactLine,
        ResidualFlexibility, SharedStiffnessAnalysis, StiffnessFactor, TrackStructure,
    };
    /// The plane flexibilities from whitened loads (forward substitution over the reached
    /// supernodes) against the same quadratic forms from full solves and the nodes' weighted
    /// displacements (faer's forward and backward substitution), on the small test track:
    /// agreement to round-off (1e-10 relative); a factor sharing the first one's analysis
    /// gives the same values for a changed railpad stiffness as its own analysis.
    #[test]
    fn whitened_plane_flexibility_matches_full_solves() {
        let m = crate::model::test_problems::small_model(&[]).unwrap();
        let track = TrackStructure::build(&m).unwrap();
        let (mats, _) = track.assemble().unwrap();
        let factor = StiffnessFactor::new(mats.k.as_ref()).unwrap();
        let frame = ContactFrame::for_inclination(m.rail.inclination);
        let empty = Mat::<f64>::zeros(track.dofmap.n_free(), 0);
        let line = RailContactLine::new(&track, &empty, &frame, 0.005).unwrap();
        let (p0, p1) = (2, 2 + 10);
        let (g, cross) = static_flexibility(&track, &factor, &line, &frame, p0, p1).unwrap();
        let axes = [frame.x, frame.t, frame.n];
        let (mut g_ref, mut c_ref) = (vec![[0.0; 3]; 11], vec![[0.0; 3]; 10]);
        for_each_plane_solution(&track, &factor, &line, &frame, p0, p1, &mut |i, d, u| {
            g_ref[i][d] = nodes_dot(&line.nodes[p0 + i], &track.dofmap, axes[d], u);
            if i < 10 {
                c_ref[i][d] = nodes_dot(&line.nodes[p0 + i + 1], &track.dofmap, axes[d], u);
            }
        });
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * b.abs();
        for i in 0..11 {
            for d in 0..3 {
                assert!(
                    close(g[i][d], g_ref[i][d]),
                    "G {i} {d}: {} vs {}",
                    g[i][d],
                    g_ref[i][d]
                );
                if i < 10 {
                    assert!(close(cross[i][d], c_ref[i][d]), "cross {i} {d}");
                }
            }
        }
        let shared = SharedStiffnessAnalysis::default();
        shared.factor(mats.k.as_ref()).unwrap();
        let m2 = crate::model::test_problems::small_model(&["fastening.vertical_stiffness=9e8"])
            .unwrap();
        let track2 = TrackStructure::build(&m2).unwrap();
        let (mats2, _) = track2.assemble().unwrap();
        let own = StiffnessFactor::new(mats2.k.as_ref()).unwrap();
        let reused = shared.factor(mats2.k.as_ref()).unwrap();
        let a = static_flexibility(&track2, &own, &line, &frame, p0, p1).unwrap();
        let b = static_flexibility(&track2, &reused, &line, &frame, p0, p1).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.0, g, "the stiffness change must change the flexibility");
    }

    /// Hand-computed: two intervals of 10 and 30 mm with mid-element residuals
    /// ¼(R_i + R_{i+1} + 2 R_{i,i+1}); the constant compliance is their length-weighted mean.
    #[test]
    fn constant_compliance_is_the_length_weighted_mean_of_the_mid_element_values() {
        let r = ResidualFlexibility {
            first_plane: 0,
            planes_x_m: vec![0.0, 0.01, 0.04],
            static_m_per_n: vec![[4e-10, 2e-10, 8e-10]; 3],
            modal_m_per_n: vec![[0.0; 3], [2e-10, 0.0, 4e-10], [0.0; 3]],
            cross_residual_m_per_n: vec![[1e-10, 1e-10, 2e-10], [3e-10, 1e-10, 4e-10]],
            modes: 0,
        };
        // residuals per plane: [4, 2, 8], [2, 2, 4], [4, 2, 8] (×1e-10)
        let m0 = [
            0.25 * (4.0 + 2.0 + 2.0),
            0.25 * (2.0 + 2.0 + 2.0),
            0.25 * (8.0 + 4.0 + 4.0),
        ];
        let m1 = [
            0.25 * (2.0 + 4.0 + 6.0),
            0.25 * (2.0 + 2.0 + 2.0),
            0.25 * (4.0 + 8.0 + 8.0),
        ];
        let c = r.mean_structural_weighted();
        for d in 0..3 {
            let want = 1e-10 * (0.01 * m0[d] + 0.03 * m1[d]) / 0.04;
            assert!((c[d] - want).abs() < 1e-22, "{d}: {} vs {want}", c[d]);
        }
    }
}
