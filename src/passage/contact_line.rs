//! The contact's line on the rail and its point on the wheel, shared by both passage engines
//! (docs/theory.md §7.1).
//!
//! **Contact frame.** With the rail inclined by α (`rail.inclination` = tan α, head towards
//! −y) and the wheel cone of the same slope, the contact normal is `n = (0, −sin α, cos α)`
//! (outward from the rail, pointing at the wheel) and the lateral tangent is
//! `t = (0, cos α, sin α)`; `x` is the rolling direction. The contact point on the rail is
//! the running-surface node line that is the support point of the inclined section in
//! direction `n` (the crown top rotated by α).
//!
//! **Interpolation.** The rail displacement "at the contact" is a weighted sum of
//! running-surface node displacements: across the rail, weights of the Hertz pressure
//! `p ∝ √(1 − s²/b²)` integrated against the linear shape functions of the surface edges
//! (a point when b is smaller than the node spacing); along the rail, the hexahedron's linear
//! shape function between the two node planes around `x_c`. The same weights distribute the
//! contact force onto the nodes (virtual work: the force and the displacement are
//! interpolated consistently). Spreading over the patch width keeps the coarse mesh's
//! local flexibility under a point load out of the model; the contact solver's half-space
//! supplies the local (Hertzian) compliance (docs/theory.md §7.1 and
//! §7.7).

use faer::Mat;

use super::PassageError;
use crate::contact::hertz::lateral_weights;
use crate::fe::assembly::DofMap;
use crate::structure::{TrackStructure, WheelStructure};

/// The contact frame (unit vectors in global coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactFrame {
    /// Rolling direction (1, 0, 0).
    pub x: [f64; 3],
    /// Lateral tangent `(0, cos α, sin α)`.
    pub t: [f64; 3],
    /// Normal `(0, −sin α, cos α)`, from the rail towards the wheel.
    pub n: [f64; 3],
}

impl ContactFrame {
    /// The frame for a rail inclination `tan α` (−).
    pub fn for_inclination(tan_alpha: f64) -> Self {
        let a = tan_alpha.atan();
        ContactFrame {
            x: [1.0, 0.0, 0.0],
            t: [0.0, a.cos(), a.sin()],
            n: [0.0, -a.sin(), a.cos()],
        }
    }

    fn axes(&self) -> [[f64; 3]; 3] {
        [self.x, self.t, self.n]
    }
}

/// Modal rows of a weighted set of nodes: `rows[d·m + i] = Σ_k w_k n_d · φ_i(node_k)` for the
/// three axes `d` of the frame (x, t, n). Constrained DOFs contribute zero.
pub fn modal_rows(
    nodes: &[(usize, f64)],
    dofmap: &DofMap,
    modes: &Mat<f64>,
    frame: &ContactFrame,
    out: &mut [f64],
) {
    let m = modes.ncols();
    out.iter_mut().for_each(|v| *v = 0.0);
    for (d, axis) in frame.axes().iter().enumerate() {
        for &(node, w) in nodes {
            for (c, &a) in axis.iter().enumerate() {
                if a == 0.0 {
                    continue;
                }
                if let Some(f) = dofmap.free_index(3 * node + c) {
                    let row = modes.row(f);
                    for i in 0..m {
                        out[d * m + i] += w * a * row[i];
                    }
                }
            }
        }
    }
}

/// Adds `weight · Σ_k w_k (Σ_d force_d · axis_d)` on the nodes `(node, w_k)` into the free-DOF
/// load vector `f` (constrained DOFs dropped): a contact-frame force (N) spread like the
/// contact load of one node plane.
pub fn add_nodes_load(
    nodes: &[(usize, f64)],
    dofmap: &DofMap,
    frame: &ContactFrame,
    weight: f64,
    force: [f64; 3],
    f: &mut [f64],
) {
    let axes = frame.axes();
    for &(node, w) in nodes {
        for c in 0..3 {
            let g: f64 = (0..3).map(|d| force[d] * axes[d][c]).sum();
            if g == 0.0 {
                continue;
            }
            if let Some(i) = dofmap.free_index(3 * node + c) {
                f[i] += weight * w * g;
            }
        }
    }
}

/// The rail's running-surface contact line: for every node plane the modal rows (x, t, n) of
/// the weighted contact nodes, and the plane positions.
#[derive(Clone, Debug)]
pub struct RailContactLine {
    /// Node plane positions along the rail (m).
    pub planes_x_m: Vec<f64>,
    /// Number of track modes.
    pub modes: usize,
    /// Rows per plane, `3·m` values each (x, t, n blocks).
    rows: Vec<f64>,
    /// The contact nodes of each plane with their lateral weights (global node indices).
    pub nodes: Vec<Vec<(usize, f64)>>,
    /// Height of the contact point above the foot underside (m) (for output).
    pub contact_point_yz_m: [f64; 2],
}

impl RailContactLine {
    /// Builds the line for the track's modes; `half_width_m` is the Hertz semi-axis b across
    /// the rail (m).
    pub fn new(
        track: &TrackStructure,
        modes: &Mat<f64>,
        frame: &ContactFrame,
        half_width_m: f64,
    ) -> Result<Self, PassageError> {
        let topo = &track.rail;
        let sec = &topo.section;
        if sec.running_surface.is_empty() {
            return Err(PassageError::MissingNodes {
                what: "running-surface nodes in the rail section",
            });
        }
        // Support point in direction n.
        let score = |j: usize| {
            let [y, z] = sec.nodes[j];
            frame.n[1] * y + frame.n[2] * z
        };
        let jc = *sec
            .running_surface
            .iter()
            .max_by(|&&a, &&b| score(a).total_cmp(&score(b)))
            .expect("non-empty");
        let [yc, zc] = sec.nodes[jc];
        // Lateral coordinate along the tangent t relative to the contact point.
        let mut lat: Vec<(f64, usize)> = sec
            .running_surface
            .iter()
            .map(|&j| {
                let [y, z] = sec.nodes[j];
                (frame.t[1] * (y - yc) + frame.t[2] * (z - zc), j)
            })
            .collect();
        lat.sort_by(|a, b| a.0.total_cmp(&b.0));
        let s: Vec<f64> = lat.iter().map(|v| v.0).collect();
        let w = lateral_weights(&s, half_width_m);
        let m = modes.ncols();
        let np = topo.n_planes();
        let mut rows = vec![0.0; np * 3 * m];
        let mut nodes = Vec::with_capacity(np);
        for p in 0..np {
            let set: Vec<(usize, f64)> = lat
                .iter()
                .zip(&w)
                .filter(|(_, &wk)| wk > 0.0)
                .map(|(&(_, j), &wk)| (topo.node(p, j), wk))
                .collect();
            modal_rows(
                &set,
                &track.dofmap,
                modes,
                frame,
                &mut rows[p * 3 * m..(p + 1) * 3 * m],
            );
            nodes.push(set);
        }
        Ok(RailContactLine {
            planes_x_m: topo.planes_x_m.clone(),
            modes: m,
            rows,
            nodes,
            contact_point_yz_m: [yc, zc],
        })
    }

    /// [`PassageError::OffRail`] for `what` at `x` (m), with the rail's extent.
    pub fn off_rail(&self, what: &'static str, x: f64) -> PassageError {
        PassageError::OffRail {
            what,
            x_m: x,
            start_m: self.planes_x_m[0],
            end_m: self.planes_x_m[self.planes_x_m.len() - 1],
        }
    }

    /// The modal rows (x, t, n blocks, `3·m` values) of node plane `p` (`p <` the plane
    /// count).
    pub fn plane_rows(&self, p: usize) -> &[f64] {
        let k = 3 * self.modes;
        &self.rows[p * k..(p + 1) * k]
    }

    /// Interval and linear weight of `x` (m): `(p, s)` with `x = (1−s)·x_p + s·x_{p+1}`;
    /// `None` off the rail.
    pub fn locate(&self, x: f64) -> Option<(usize, f64)> {
        let px = &self.planes_x_m;
        if !(x >= px[0] && x <= px[px.len() - 1]) {
            return None;
        }
        let p = px.partition_point(|&v| v <= x).clamp(1, px.len() - 1) - 1;
        Some((p, (x - px[p]) / (px[p + 1] - px[p])))
    }

    /// The interpolated rows at `x` (m) into `out` (length 3m). No allocation.
    pub fn rows_at(&self, x: f64, out: &mut [f64]) -> Result<(), PassageError> {
        let (p, s) = self
            .locate(x)
            .ok_or_else(|| self.off_rail("contact point", x))?;
        let k = 3 * self.modes;
        let a = &self.rows[p * k..(p + 1) * k];
        let b = &self.rows[(p + 1) * k..(p + 2) * k];
        for i in 0..k {
            out[i] = (1.0 - s) * a[i] + s * b[i];
        }
        Ok(())
    }
}

impl RailContactLine {
    /// Derivative along x of the interpolated rows at `x` (1/m): `(row_{p+1} − row_p)/Δx_p`
    /// for the two planes around x, into `out` (length 3m; d/dx of the linear interpolation).
    pub fn row_slopes_at(&self, x: f64, out: &mut [f64]) -> Result<(), PassageError> {
        let (p, _) = self
            .locate(x)
            .ok_or_else(|| self.off_rail("contact point", x))?;
        let k = 3 * self.modes;
        let h = self.planes_x_m[p + 1] - self.planes_x_m[p];
        let a = &self.rows[p * k..(p + 1) * k];
        let b = &self.rows[(p + 1) * k..(p + 2) * k];
        for i in 0..k {
            out[i] = (b[i] - a[i]) / h;
        }
        Ok(())
    }
}

/// The wheel side of the contact: modal rows (x, t, n) of the weighted tread nodes at the
/// nominal contact point, and of the journal (axle-box) centre in x.
#[derive(Clone, Debug)]
pub struct WheelContact {
    /// Rows of the contact point, `3·m` values (x, t, n blocks).
    pub rows: Vec<f64>,
    /// Row of the x displacement of the axle centre (journal nodes with balanced weights,
    /// see [`crate::structure::wheel::balanced_journal_weights`]) (m values).
    pub axle_x: Vec<f64>,
    /// The tread nodes and weights used.
    pub nodes: Vec<(usize, f64)>,
}

impl WheelContact {
    /// The tread nodes of the ring at angle index `k` with the lateral weights of the Hertz
    /// pressure of semi-width `half_width_m` (m) ([`lateral_weights`]); the contact load sits
    /// on the ring at θ = 0.
    pub fn ring_nodes(wheel: &WheelStructure, k: usize, half_width_m: f64) -> Vec<(usize, f64)> {
        let topo = &wheel.topology;
        let mut lat: Vec<(f64, usize)> = topo
            .tread_meridian
            .iter()
            .map(|&mi| (topo.meridian[mi][0], topo.node(k, mi)))
            .collect();
        lat.sort_by(|a, b| a.0.total_cmp(&b.0));
        let s: Vec<f64> = lat.iter().map(|v| v.0).collect();
        let w = lateral_weights(&s, half_width_m);
        lat.iter()
            .zip(&w)
            .filter(|(_, &wk)| wk > 0.0)
            .map(|(&(_, nd), &wk)| (nd, wk))
            .collect()
    }

    /// Builds the wheel contact rows for the wheel's modes; `half_width_m` as for the rail.
    pub fn new(
        wheel: &WheelStructure,
        modes: &Mat<f64>,
        frame: &ContactFrame,
        half_width_m: f64,
    ) -> Result<Self, PassageError> {
        let topo = &wheel.topology;
        let nodes = Self::ring_nodes(wheel, topo.contact_angle_index(), half_width_m);
        let m = modes.ncols();
        let mut rows = vec![0.0; 3 * m];
        modal_rows(&nodes, &wheel.dofmap, modes, frame, &mut rows);
        let bearing = topo.bearing_nodes();
        if bearing.is_empty() {
            return Err(PassageError::MissingNodes {
                what: "journal nodes on the wheel",
            });
        }
        let wb = crate::structure::wheel::balanced_journal_weights(&wheel.mesh, &bearing);
        let bset: Vec<(usize, f64)> = bearing.iter().copied().zip(wb).collect();
        let mut ax = vec![0.0; 3 * m];
        modal_rows(&bset, &wheel.dofmap, modes, frame, &mut ax);
        ax.truncate(m);
        Ok(WheelContact {
            rows,
            axle_x: ax,
            nodes,
        })
    }
}

/// `Σ_i a_i b_i`.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Adds the free-DOF load vector of `force` (N, on the rail, components along the frame
/// axes x, t, n) at `x` (m) on the contact line into `f` (length n_free): the contact-line
/// weights across the rail times the linear shape functions of the two planes around `x`.
pub fn add_line_load(
    track: &TrackStructure,
    line: &RailContactLine,
    frame: &ContactFrame,
    x: f64,
    force: [f64; 3],
    f: &mut [f64],
) -> Result<(), PassageError> {
    let (p, s) = line.locate(x).ok_or_else(|| line.off_rail("load", x))?;
    for (plane, np) in [(p, 1.0 - s), (p + 1, s)] {
        if np != 0.0 {
            add_nodes_load(&line.nodes[plane], &track.dofmap, frame, np, force, f);
        }
    }
    Ok(())
}

/// The free-DOF load vector (N) of `force` (N, on the rail, contact-frame components x, t, n)
/// at `x` (m) on the contact line: what a direct solution of the full matrices applies. Its projection `Φᵀ f` equals
/// `Σ_d F_d rows_d(x)` of [`RailContactLine::rows_at`] (tested).
pub fn line_load_vector(
    track: &TrackStructure,
    line: &RailContactLine,
    frame: &ContactFrame,
    x: f64,
    force: [f64; 3],
) -> Result<Vec<f64>, PassageError> {
    let mut f = vec![0.0; track.dofmap.n_free()];
    add_line_load(track, line, frame, x, force, &mut f)?;
    Ok(f)
}
