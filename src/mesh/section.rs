//! Block-structured quadrilateral mesh of the full (symmetric) UIC54 cross-section.
//!
//! Blocks (right half, mirrored to the left; the centre blocks span both halves):
//!
//! | block | boundaries |
//! |---|---|
//! | foot arm | foot underside (y_c … 70 mm), foot edge, foot top + fishing face + lower part of the R16 fillet up to M, straight interface M → (y_c, 0) |
//! | foot centre | foot underside (−y_c … y_c), the two interfaces, the line M_L → M_R |
//! | web | M_L → M_R, the sides M → (R16) → web face → (R22) → N, the line N_L → N_R |
//! | head centre | N_L → N_R, straight interfaces N → T, the cap bottom T_L → T_R at z = z_c |
//! | head arm | lower R22 fillet + head underside N → H → I, head side I → S (z = z_c), cap bottom S → T, interface T → N |
//! | cap | cap bottom line z = z_c, head sides S → J, running surface J_L → J_R |
//!
//! M and N are the points of the R16 / R22 fillets 45° from the web, so every block corner
//! has a reasonable angle. y_c is the web half thickness, snapped to a required foot node line
//! within a quarter of an element of it (a line farther off is a node line of the foot arm: a
//! snap over up to half an element left elements of about a millimetre beside the web, which set
//! the explicit path's stable step). The foot arm and foot centre bottoms are graded 1D
//! distributions ([`crate::mesh::grading`]) holding the required foot node lines; the foot
//! centre's count fixes the web's lateral count. The cap is meshed in vertical columns under
//! the running-surface nodes (graded along the head top: fine near the centre) with layers
//! graded from the running surface downwards; its bottom line takes the columns' y, so the
//! head arm and head centre blocks absorb the change of lateral resolution from the web to the
//! running surface. Interiors of the four-sided blocks are filled by discrete transfinite
//! interpolation with blended boundary parameters (Thompson, Warsi & Mastin, *Numerical Grid
//! Generation*, 1985, §8.4; Soni, "Two- and three-dimensional grid generation for internal
//! flow applications", AIAA 85-1526).
//!
//! All nodes on the profile lie on the profile polyline; the section deviates from the
//! polygon only where a chord between two boundary nodes cuts a curved part (fillets, head
//! top). Optional inclination: rotation about the foot centre (0, 0) by the inclination angle
//! (1/40 rail: atan(1/40) = 1.432°), the head tilting towards −y (the track centre).
//!
//! Section properties are integrated over the bilinear quads with the 2×2 Gauss rule, exact
//! for area, first and second moments of bilinear quads (the integrands are of degree ≤ 3 in
//! each natural coordinate).

mod blocks;

use blocks::{check_params, foot_lines, Blocks, Outline};

use super::profile::{RailProfile, SectionProperties};
use super::MeshError;
use std::collections::HashMap;

/// Parameters of the section mesh (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionParams {
    /// Target element size in the foot, web and head body (m).
    pub size_m: f64,
    /// Element size at the running surface (m), laterally and in depth.
    pub running_surface_size_m: f64,
    /// Half width of the fine running-surface zone, measured along the head top from the
    /// head centre (m).
    pub running_surface_half_width_m: f64,
    /// Depth below the running surface over which the fine size holds (m).
    pub running_surface_depth_m: f64,
    /// Lateral positions (m, in the rail's own upright frame, from the foot centre) that must
    /// be node lines on the foot underside; they are mirrored (±y) so the mesh stays symmetric.
    pub foot_node_lines_m: Vec<f64>,
    /// Rail inclination (rad) about the foot centre, head towards −y; 0 = upright,
    /// atan(1/40) for the usual 1:40 inclination.
    pub inclination_rad: f64,
}

impl Default for SectionParams {
    fn default() -> Self {
        SectionParams {
            size_m: 0.005,
            running_surface_size_m: 0.0025,
            running_surface_half_width_m: 0.020,
            running_surface_depth_m: 0.004,
            foot_node_lines_m: Vec::new(),
            inclination_rad: 0.0,
        }
    }
}

/// The meshed cross-section.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionMesh {
    /// Node coordinates (y, z) in m (after the inclination, if any).
    pub nodes: Vec<[f64; 2]>,
    /// Quadrilaterals, counter-clockwise in the (y, z) plane.
    pub quads: Vec<[usize; 4]>,
    /// Nodes on the foot underside, ordered by their position along the foot.
    pub foot_underside: Vec<usize>,
    /// Position of each [`Self::foot_underside`] node along the foot underside from the foot
    /// centre (m; equals y for an upright rail).
    pub foot_underside_s_m: Vec<f64>,
    /// Nodes of the head top (running surface, from one end of the head side round to the
    /// other), ordered by y.
    pub running_surface: Vec<usize>,
    /// The inclination applied (rad).
    pub inclination_rad: f64,
}

// ---------------------------------------------------------------------------------------------
// Polylines

#[derive(Debug, Clone)]
struct Polyline {
    pts: Vec<[f64; 2]>,
    cum: Vec<f64>,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

impl Polyline {
    fn new(pts: Vec<[f64; 2]>) -> Self {
        let mut cum = Vec::with_capacity(pts.len());
        let mut s = 0.0;
        cum.push(0.0);
        for w in pts.windows(2) {
            s += dist(w[0], w[1]);
            cum.push(s);
        }
        Polyline { pts, cum }
    }
    fn len(&self) -> f64 {
        *self.cum.last().expect("non-empty")
    }
    fn at(&self, s: f64) -> [f64; 2] {
        let s = s.clamp(0.0, self.len());
        let k = match self.cum.iter().position(|&c| c >= s) {
            Some(0) => return self.pts[0],
            Some(k) => k,
            None => return *self.pts.last().expect("non-empty"),
        };
        let t = (s - self.cum[k - 1]) / (self.cum[k] - self.cum[k - 1]);
        lerp(self.pts[k - 1], self.pts[k], t)
    }
    fn sub(&self, s0: f64, s1: f64) -> Polyline {
        let mut pts = vec![self.at(s0)];
        for (k, &c) in self.cum.iter().enumerate() {
            if c > s0 && c < s1 {
                pts.push(self.pts[k]);
            }
        }
        pts.push(self.at(s1));
        Polyline::new(pts)
    }
    fn reversed(&self) -> Polyline {
        let mut p = self.pts.clone();
        p.reverse();
        Polyline::new(p)
    }
    fn join(&self, other: &Polyline) -> Polyline {
        let mut p = self.pts.clone();
        p.extend_from_slice(&other.pts[1..]);
        Polyline::new(p)
    }
    /// n + 1 points uniformly spaced in arc length.
    fn uniform(&self, n: usize) -> Vec<[f64; 2]> {
        let l = self.len();
        let mut v: Vec<[f64; 2]> = (0..=n).map(|k| self.at(l * k as f64 / n as f64)).collect();
        v[0] = self.pts[0];
        v[n] = *self.pts.last().expect("non-empty");
        v
    }
    /// The point with lateral coordinate y of a polyline that is a graph over y.
    fn at_y(&self, y: f64) -> [f64; 2] {
        for w in self.pts.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (lo, hi) = if a[0] <= b[0] {
                (a[0], b[0])
            } else {
                (b[0], a[0])
            };
            if y >= lo && y <= hi && hi > lo {
                return lerp(a, b, (y - a[0]) / (b[0] - a[0]));
            }
        }
        // Outside: nearest end.
        let (a, b) = (self.pts[0], *self.pts.last().expect("non-empty"));
        if (y - a[0]).abs() < (y - b[0]).abs() {
            a
        } else {
            b
        }
    }
}

fn straight(a: [f64; 2], b: [f64; 2], n: usize) -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = (0..=n).map(|k| lerp(a, b, k as f64 / n as f64)).collect();
    v[0] = a;
    v[n] = b;
    v
}

fn mirror(v: &[[f64; 2]]) -> Vec<[f64; 2]> {
    v.iter().map(|p| [-p[0], p[1]]).collect()
}

fn arc_fractions(v: &[[f64; 2]]) -> Vec<f64> {
    let mut c = vec![0.0; v.len()];
    for k in 1..v.len() {
        c[k] = c[k - 1] + dist(v[k - 1], v[k]);
    }
    let l = c[v.len() - 1];
    c.iter().map(|x| x / l).collect()
}

/// A structured block: (n + 1) × (m + 1) points, `pts[j * (n + 1) + i]`, i along the
/// bottom/top, j along the left/right sides.
struct Grid {
    n: usize,
    m: usize,
    pts: Vec<[f64; 2]>,
}

/// Discrete transfinite interpolation from the four boundaries (bottom and top run from the
/// left side to the right side, left and right from the bottom to the top).
fn tfi(bottom: &[[f64; 2]], right: &[[f64; 2]], top: &[[f64; 2]], left: &[[f64; 2]]) -> Grid {
    let n = bottom.len() - 1;
    let m = left.len() - 1;
    debug_assert_eq!(top.len(), n + 1);
    debug_assert_eq!(right.len(), m + 1);
    let (sb, st, sl, sr) = (
        arc_fractions(bottom),
        arc_fractions(top),
        arc_fractions(left),
        arc_fractions(right),
    );
    let (p00, p10, p01, p11) = (bottom[0], bottom[n], top[0], top[n]);
    let mut pts = vec![[0.0; 2]; (n + 1) * (m + 1)];
    for j in 0..=m {
        for i in 0..=n {
            let p = if j == 0 {
                bottom[i]
            } else if j == m {
                top[i]
            } else if i == 0 {
                left[j]
            } else if i == n {
                right[j]
            } else {
                let den = 1.0 - (st[i] - sb[i]) * (sr[j] - sl[j]);
                let xi = (sb[i] + sl[j] * (st[i] - sb[i])) / den;
                let eta = (sl[j] + sb[i] * (sr[j] - sl[j])) / den;
                let mut q = [0.0; 2];
                for d in 0..2 {
                    q[d] = (1.0 - eta) * bottom[i][d]
                        + eta * top[i][d]
                        + (1.0 - xi) * left[j][d]
                        + xi * right[j][d]
                        - ((1.0 - xi) * (1.0 - eta) * p00[d]
                            + xi * (1.0 - eta) * p10[d]
                            + (1.0 - xi) * eta * p01[d]
                            + xi * eta * p11[d]);
                }
                q
            };
            pts[j * (n + 1) + i] = p;
        }
    }
    Grid { n, m, pts }
}

/// Node and quad accumulator that merges coincident nodes (shared block edges are computed
/// once and passed to both blocks, so coincident nodes are bit-identical up to the sign of 0).
#[derive(Default)]
struct Builder {
    nodes: Vec<[f64; 2]>,
    index: HashMap<(i64, i64), usize>,
    quads: Vec<[usize; 4]>,
}

impl Builder {
    fn node(&mut self, p: [f64; 2]) -> usize {
        let key = ((p[0] * 1e10).round() as i64, (p[1] * 1e10).round() as i64);
        let next = self.nodes.len();
        *self.index.entry(key).or_insert_with(|| {
            self.nodes.push(p);
            next
        })
    }
    /// Adds a grid; `flip` reverses the orientation (mirrored blocks).
    fn add(&mut self, g: &Grid, flip: bool) {
        let ids: Vec<usize> = g.pts.iter().map(|&p| self.node(p)).collect();
        let w = g.n + 1;
        for j in 0..g.m {
            for i in 0..g.n {
                let (a, b, c, d) = (
                    ids[j * w + i],
                    ids[j * w + i + 1],
                    ids[(j + 1) * w + i + 1],
                    ids[(j + 1) * w + i],
                );
                self.quads
                    .push(if flip { [a, d, c, b] } else { [a, b, c, d] });
            }
        }
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> MeshError {
    MeshError::InvalidParameter {
        name,
        value,
        reason,
    }
}

fn vertex(half: &[[f64; 2]], y_mm: f64, z_mm: f64) -> Result<usize, MeshError> {
    half.iter()
        .position(|p| {
            (p[0] - crate::units::mm_to_m(y_mm)).abs() < 1e-6
                && (p[1] - crate::units::mm_to_m(z_mm)).abs() < 1e-6
        })
        .ok_or(MeshError::ProfileParse {
            line: 0,
            reason: format!("the section mesher needs the UIC54 key point ({y_mm}, {z_mm}) mm"),
        })
}

/// Arc fraction of the R16/R22 fillets (both 70° arcs) from the web to the block corner
/// 45° from the web.
const FILLET_SPLIT_FROM_WEB: f64 = 45.0 / 70.0;

/// The share of a section element within which the web's boundary in the foot snaps to a
/// required foot node line (module doc).
const WEB_SNAP_SHARE: f64 = 0.25;

/// The web's boundary in the foot `y_c` (m): the web half thickness `web_half`, or the required
/// foot node line (of `lines`, m, `y ≥ 0`) nearest to it within `reach` (m).
fn web_boundary(lines: &[f64], web_half: f64, reach: f64) -> f64 {
    lines
        .iter()
        .copied()
        .filter(|&y| y > 0.0 && (y - web_half).abs() <= reach)
        .min_by(|a, b| (a - web_half).abs().total_cmp(&(b - web_half).abs()))
        .unwrap_or(web_half)
}

impl SectionMesh {
    /// Meshes the embedded UIC54 profile.
    pub fn uic54(params: &SectionParams) -> Result<Self, MeshError> {
        Self::build(&RailProfile::uic54()?, params)
    }

    /// Meshes a UIC54-topology profile (it must contain the UIC54 key points: foot edge,
    /// fishing-face ends, fillet ends, head corners).
    ///
    /// Phases: the parameters checked, the profile's outline cut into the blocks' boundary
    /// pieces, the required foot node lines and the web half thickness, then the blocks in
    /// the order foot arms, foot centre, web, cap, head centre and head arms (each sharing
    /// its edges with the blocks meshed before), and last the foot underside and the
    /// inclination.
    pub fn build(profile: &RailProfile, params: &SectionParams) -> Result<Self, MeshError> {
        check_params(params)?;
        let o = Outline::new(profile)?;
        let h = params.size_m;
        let lines = foot_lines(params, o.foot_half_w)?;
        let yc = web_boundary(&lines, o.pf[0], WEB_SNAP_SHARE * h);
        let mut blocks = Blocks {
            o: &o,
            params,
            h,
            yc,
            lines: &lines,
            b: Builder::default(),
        };
        let arm_left = blocks.foot_arms()?;
        let (web_bottom, n_w) = blocks.foot_centre(&arm_left)?;
        let web_top = blocks.web(&web_bottom, n_w);
        let cap = blocks.cap(n_w)?;
        blocks.head(&cap, &web_top, n_w);
        let mut b = blocks.b;

        // ---- foot underside ----
        let mut foot: Vec<(f64, usize)> = b
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, p)| p[1] == 0.0)
            .map(|(k, p)| (p[0], k))
            .collect();
        foot.sort_by(|a, b| a.0.total_cmp(&b.0));

        let inc = params.inclination_rad;
        let (c, s) = (inc.cos(), inc.sin());
        let nodes: Vec<[f64; 2]> = b
            .nodes
            .iter()
            .map(|p| [p[0] * c - p[1] * s, p[0] * s + p[1] * c])
            .collect();
        let mesh = SectionMesh {
            nodes,
            quads: std::mem::take(&mut b.quads),
            foot_underside: foot.iter().map(|f| f.1).collect(),
            foot_underside_s_m: foot.iter().map(|f| f.0).collect(),
            running_surface: cap.running,
            inclination_rad: inc,
        };
        mesh.check_quads()?;
        Ok(mesh)
    }

    /// Checks every quad is strictly convex and counter-clockwise.
    pub(crate) fn check_quads(&self) -> Result<(), MeshError> {
        for (q, quad) in self.quads.iter().enumerate() {
            let p = quad.map(|n| self.nodes[n]);
            for k in 0..4 {
                let (a, b, c) = (p[k], p[(k + 1) % 4], p[(k + 2) % 4]);
                let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
                if cross.is_nan() || cross <= 0.0 {
                    return Err(MeshError::InvalidElement {
                        reason: format!(
                            "section quad {q} is not convex/counter-clockwise at its corner {}",
                            (k + 1) % 4
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    /// Section properties by 2×2 Gauss integration over the quads.
    pub fn properties(&self) -> SectionProperties {
        let g = 1.0 / 3f64.sqrt();
        let (mut a, mut sy, mut sz, mut syy, mut szz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for quad in &self.quads {
            let p = quad.map(|n| self.nodes[n]);
            for xi in [-g, g] {
                for eta in [-g, g] {
                    let (y, z, det) = bilinear(&p, xi, eta);
                    a += det;
                    sy += y * det;
                    sz += z * det;
                    syy += y * y * det;
                    szz += z * z * det;
                    syz += y * z * det;
                }
            }
        }
        SectionProperties::from_integrals(a, sy, sz, syy, szz, syz)
    }

    /// Quality of the quads: (smallest interior angle, largest interior angle) in degrees and
    /// the largest ratio of longest to shortest edge.
    pub fn quality(&self) -> (f64, f64, f64) {
        let (mut amin, mut amax, mut ratio) = (180.0f64, 0.0f64, 1.0f64);
        for quad in &self.quads {
            let p = quad.map(|n| self.nodes[n]);
            let (mut emin, mut emax) = (f64::INFINITY, 0.0f64);
            for k in 0..4 {
                let (a, b, c) = (p[(k + 3) % 4], p[k], p[(k + 1) % 4]);
                let u = [a[0] - b[0], a[1] - b[1]];
                let v = [c[0] - b[0], c[1] - b[1]];
                let cosang = (u[0] * v[0] + u[1] * v[1]) / (dist(a, b) * dist(b, c));
                let ang = cosang.clamp(-1.0, 1.0).acos().to_degrees();
                amin = amin.min(ang);
                amax = amax.max(ang);
                emin = emin.min(dist(b, c));
                emax = emax.max(dist(b, c));
            }
            ratio = ratio.max(emax / emin);
        }
        (amin, amax, ratio)
    }

    /// Area (m²) of quad `q`.
    pub fn quad_area(&self, q: usize) -> f64 {
        let p = self.quads[q].map(|n| self.nodes[n]);
        0.5 * ((p[2][0] - p[0][0]) * (p[3][1] - p[1][1])
            - (p[3][0] - p[1][0]) * (p[2][1] - p[0][1]))
    }

    /// Finds the quad containing the point (y, z) (m) and its natural coordinates (ξ, η) in
    /// [−1, 1]²; `None` if the point is outside the section (tolerance 1e-9 in ξ, η).
    pub fn locate(&self, y: f64, z: f64) -> Option<(usize, [f64; 2])> {
        for (q, quad) in self.quads.iter().enumerate() {
            let p = quad.map(|n| self.nodes[n]);
            let (lo_y, hi_y) = p
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), v| {
                    (l.min(v[0]), u.max(v[0]))
                });
            let (lo_z, hi_z) = p
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), v| {
                    (l.min(v[1]), u.max(v[1]))
                });
            let eps = 1e-12;
            if y < lo_y - eps || y > hi_y + eps || z < lo_z - eps || z > hi_z + eps {
                continue;
            }
            if let Some(nat) = invert_bilinear(&p, y, z) {
                if nat[0].abs() <= 1.0 + 1e-9 && nat[1].abs() <= 1.0 + 1e-9 {
                    return Some((q, nat));
                }
            }
        }
        None
    }
}

/// A uniform bucket grid over a section mesh for fast point location: each bucket lists the
/// quads whose bounding box overlaps it.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionLocator {
    lo: [f64; 2],
    cell: [f64; 2],
    n: [usize; 2],
    start: Vec<usize>,
    items: Vec<usize>,
}

impl SectionLocator {
    /// Builds the bucket grid (about one quad per bucket).
    pub fn new(mesh: &SectionMesh) -> Self {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &mesh.nodes {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let side = ((mesh.quads.len() as f64).sqrt().ceil() as usize).max(1);
        let n = [side, side];
        let cell = [
            ((hi[0] - lo[0]) / side as f64).max(1e-12),
            ((hi[1] - lo[1]) / side as f64).max(1e-12),
        ];
        let mut buckets: Vec<Vec<usize>> = vec![Vec::new(); n[0] * n[1]];
        let idx =
            |v: f64, d: usize| (((v - lo[d]) / cell[d]).floor().max(0.0) as usize).min(n[d] - 1);
        for (q, quad) in mesh.quads.iter().enumerate() {
            let p = quad.map(|k| mesh.nodes[k]);
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for v in &p {
                for d in 0..2 {
                    a[d] = a[d].min(v[d]);
                    b[d] = b[d].max(v[d]);
                }
            }
            for j in idx(a[1], 1)..=idx(b[1], 1) {
                for i in idx(a[0], 0)..=idx(b[0], 0) {
                    buckets[j * n[0] + i].push(q);
                }
            }
        }
        let mut start = Vec::with_capacity(buckets.len() + 1);
        let mut items = Vec::new();
        for bk in &buckets {
            start.push(items.len());
            items.extend_from_slice(bk);
        }
        start.push(items.len());
        SectionLocator {
            lo,
            cell,
            n,
            start,
            items,
        }
    }

    /// Same result as [`SectionMesh::locate`], searching only the point's bucket.
    pub fn locate(&self, mesh: &SectionMesh, y: f64, z: f64) -> Option<(usize, [f64; 2])> {
        let fi = (y - self.lo[0]) / self.cell[0];
        let fj = (z - self.lo[1]) / self.cell[1];
        let tol = 1e-9;
        if !(fi >= -tol
            && fj >= -tol
            && fi <= self.n[0] as f64 + tol
            && fj <= self.n[1] as f64 + tol)
        {
            return None;
        }
        let i = (fi.floor().max(0.0) as usize).min(self.n[0] - 1);
        let j = (fj.floor().max(0.0) as usize).min(self.n[1] - 1);
        let b = j * self.n[0] + i;
        for &q in &self.items[self.start[b]..self.start[b + 1]] {
            let p = mesh.quads[q].map(|k| mesh.nodes[k]);
            if let Some(nat) = invert_bilinear(&p, y, z) {
                if nat[0].abs() <= 1.0 + 1e-9 && nat[1].abs() <= 1.0 + 1e-9 {
                    return Some((q, nat));
                }
            }
        }
        None
    }
}

/// Keeps the outermost column bottom on the head side (S) rather than below J.
fn col_top_fix(col_bot: &mut [[f64; 2]], ps: [f64; 2]) {
    if let Some(last) = col_bot.last_mut() {
        *last = ps;
    }
}

/// Position (y, z) and Jacobian determinant of the bilinear quad map at (ξ, η).
fn bilinear(p: &[[f64; 2]; 4], xi: f64, eta: f64) -> (f64, f64, f64) {
    const NAT: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let (mut y, mut z, mut yx, mut ye, mut zx, mut ze) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..4 {
        let (a, b) = (NAT[k][0], NAT[k][1]);
        let n = 0.25 * (1.0 + a * xi) * (1.0 + b * eta);
        let nx = 0.25 * a * (1.0 + b * eta);
        let ne = 0.25 * b * (1.0 + a * xi);
        y += n * p[k][0];
        z += n * p[k][1];
        yx += nx * p[k][0];
        ye += ne * p[k][0];
        zx += nx * p[k][1];
        ze += ne * p[k][1];
    }
    (y, z, yx * ze - ye * zx)
}

/// Newton inversion of the bilinear quad map; `None` if it does not converge.
pub(crate) fn invert_bilinear(p: &[[f64; 2]; 4], y: f64, z: f64) -> Option<[f64; 2]> {
    const NAT: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let (mut xi, mut eta) = (0.0f64, 0.0f64);
    for _ in 0..30 {
        let (mut fy, mut fz, mut yx, mut ye, mut zx, mut ze) = (-y, -z, 0.0, 0.0, 0.0, 0.0);
        for k in 0..4 {
            let (a, b) = (NAT[k][0], NAT[k][1]);
            let n = 0.25 * (1.0 + a * xi) * (1.0 + b * eta);
            fy += n * p[k][0];
            fz += n * p[k][1];
            yx += 0.25 * a * (1.0 + b * eta) * p[k][0];
            ye += 0.25 * b * (1.0 + a * xi) * p[k][0];
            zx += 0.25 * a * (1.0 + b * eta) * p[k][1];
            ze += 0.25 * b * (1.0 + a * xi) * p[k][1];
        }
        let det = yx * ze - ye * zx;
        if det.abs() < 1e-300 {
            return None;
        }
        let dxi = (ze * fy - ye * fz) / det;
        let deta = (-zx * fy + yx * fz) / det;
        xi -= dxi;
        eta -= deta;
        if !xi.is_finite() || xi.abs() > 10.0 || eta.abs() > 10.0 {
            return None;
        }
        if dxi.abs() < 1e-13 && deta.abs() < 1e-13 {
            return Some([xi, eta]);
        }
    }
    None
}

#[cfg(test)]
mod tests;
