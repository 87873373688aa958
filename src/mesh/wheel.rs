//! The wheel and half axle as a 3D solid of revolution (8-node hexahedra).
//!
//! Wheel frame: origin at the wheel centre in the plane of the nominal rolling circle, y along
//! the axle (+y towards the field side, the track centre at −y), z up, x along the direction
//! of travel; the undeformed wheel touches the rail at (0, 0, −R). A meridian point (y, r) at
//! angle θ is at (x, y, z) = (r sin θ, y, −r cos θ): θ = 0 is the contact point.
//!
//! The meridian section is a union of disjoint blocks in (y, r):
//!
//! | block | y range | r range |
//! |---|---|---|
//! | half axle | symmetry plane … journal start | bore … axle radius |
//! | journal (axle-box bearing seat) | journal start … journal end | bore … journal radius |
//! | hub | hub inner … hub outer face | axle radius … hub radius |
//! | web (straight disc) | web faces | hub radius … rim inner radius |
//! | rim | rim back face … rim front face | rim inner radius … tread r_t(y) = R − c·y |
//! | brake disc (optional, axle-mounted, solid ring) | disc faces | axle radius … disc radius |
//!
//! with conicity c = 1/40 (the radius decreases towards +y). The axle is bored (positive
//! bore radius) so no element degenerates on the axis. No flange is modelled (the tread is the cone
//! only). The blocks are cut by one tensor grid of y lines and r lines (graded, finer at the
//! tread near the rolling circle), rim rows are mapped onto the cone, and the meridian quads
//! are revolved through graded angles (finer near the contact point θ = 0).
//!
//! Default geometry (m): R 0.46, rim 0.39 … tread, y −0.070 … 0.065 (135 mm rim); web 30 mm
//! thick at y −0.045 … −0.015 from r 0.15 to 0.39; hub r 0.095 … 0.15, y −0.12 … 0.065;
//! axle r 0.03 (bore) … 0.095 from the symmetry plane y = −0.75 to 0.15; journal r 0.065,
//! y 0.15 … 0.33 (axle box centre ≈ 0.24 m outboard of the rolling circle, i.e. ≈ 1 m from the
//! track centre); one brake disc as a solid ring r 0.095 … 0.32, y −0.42 … −0.36. With steel
//! (7800 kg/m³) the half wheelset is ≈ 686 kg (without the disc ≈ 549 kg, below the
//! 600–900 kg of docs/theory.md §3.6: the disc mass stands for the axle-mounted brake disc
//! that a wheelset of that mass carries).
//!
//! Volume check (Pappus–Guldinus): V = 2π ∫∫ r dA over the meridian. The faceted mesh replaces
//! each arc by its chord, and its exact volume is Σ_k sin(Δθ_k) ∫∫ r dA (derived from the
//! trilinear map: det J = r sin Δθ per unit (y, r, t)), so V_mesh / V = Σ sin Δθ_k / 2π.

use super::grading::{grade, FineZone, GradingSpec};
use super::{Hex8, Mesh, MeshError, Part};

/// An axle-mounted brake disc modelled as a solid steel ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrakeDisc {
    /// Inner face y (m).
    pub y_start_m: f64,
    /// Outer face y (m).
    pub y_end_m: f64,
    /// Outer radius (m); the inner radius is the axle radius.
    pub outer_radius_m: f64,
}

/// Wheel geometry and mesh parameters (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct WheelParams {
    /// Nominal rolling radius R at y = 0 (m).
    pub radius_m: f64,
    /// Tread conicity c: r_t(y) = R − c y.
    pub conicity: f64,
    /// Rim inner radius (m).
    pub rim_inner_radius_m: f64,
    /// Rim back (track-centre side) face y (m), < 0.
    pub rim_y_start_m: f64,
    /// Rim front (field side) face y (m), > 0.
    pub rim_y_end_m: f64,
    /// Web faces y (m) at the hub; the web's faces at the rim are these plus
    /// [`Self::web_bend_m`].
    pub web_y_m: [f64; 2],
    /// Axial shift of the web's mid-plane from the hub to the rim (m, +y towards the field
    /// side; default 0: a straight web). A bent web follows
    /// `y_mid(r) = y_mid(hub) + bend (1 − cos πt)/2`, `t = (r − hub radius)/(rim inner radius −
    /// hub radius)`: it meets the hub and the rim at right angles, with the same axial
    /// thickness everywhere. The web's faces at the hub and at the rim must both lie strictly
    /// inside the rim's faces.
    pub web_bend_m: f64,
    /// Hub outer radius (m).
    pub hub_radius_m: f64,
    /// Hub faces y (m).
    pub hub_y_m: [f64; 2],
    /// Axle radius (m) (body and wheel seat).
    pub axle_radius_m: f64,
    /// Axle bore radius (m), > 0.
    pub bore_radius_m: f64,
    /// Distance from the rolling-circle plane to the track's symmetry plane (m): the axle
    /// starts at y = −this.
    pub symmetry_plane_distance_m: f64,
    /// Journal (bearing seat) y range (m): the axle ends at its end.
    pub journal_y_m: [f64; 2],
    /// Journal radius (m).
    pub journal_radius_m: f64,
    /// Optional brake disc.
    pub brake_disc: Option<BrakeDisc>,
    /// Largest element size along the axle (y) (m).
    pub axial_size_m: f64,
    /// Largest element size in the radial direction (m).
    pub radial_size_m: f64,
    /// Number of circumferential divisions away from the contact (the coarse angle is 2π/n).
    pub circumferential_divisions: usize,
    /// Element size at the tread near the contact: axially (|y| ≤ contact_half_width),
    /// radially (within the same depth of the tread) and circumferentially (arc length at R)
    /// (m).
    pub contact_size_m: f64,
    /// Half width (m) of the fine zone at the contact, axially, radially (depth) and along the
    /// circumference (arc length).
    pub contact_half_width_m: f64,
    /// Minimum number of element layers through the web thickness (linear hexahedra need
    /// several layers to bend well).
    pub web_layers: usize,
    /// Most nodes the mesh may have: a larger one is refused ([`MeshError::TooLarge`]) before
    /// its nodes are allocated.
    pub max_nodes: usize,
}

impl Default for WheelParams {
    fn default() -> Self {
        WheelParams {
            radius_m: 0.46,
            conicity: 1.0 / 40.0,
            rim_inner_radius_m: 0.39,
            rim_y_start_m: -0.070,
            rim_y_end_m: 0.065,
            web_y_m: [-0.045, -0.015],
            web_bend_m: 0.0,
            hub_radius_m: 0.15,
            hub_y_m: [-0.12, 0.065],
            axle_radius_m: 0.095,
            bore_radius_m: 0.03,
            symmetry_plane_distance_m: 0.75,
            journal_y_m: [0.15, 0.33],
            journal_radius_m: 0.065,
            brake_disc: Some(BrakeDisc {
                y_start_m: -0.42,
                y_end_m: -0.36,
                outer_radius_m: 0.32,
            }),
            axial_size_m: 0.05,
            radial_size_m: 0.04,
            circumferential_divisions: 36,
            contact_size_m: 0.015,
            contact_half_width_m: 0.03,
            web_layers: 3,
            max_nodes: usize::MAX,
        }
    }
}

/// A rectangle of the meridian; the rim's top is the cone.
#[derive(Debug, Clone, Copy)]
struct Block {
    y: [f64; 2],
    r: [f64; 2],
}

/// Topology of the meshed wheel.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelTopology {
    /// Meridian node coordinates (y, r) in m (tread nodes on the cone).
    pub meridian: Vec<[f64; 2]>,
    /// Node angles θ_k (rad), increasing, in (−π, π]; θ = 0 (the contact point) is one of them.
    pub thetas: Vec<f64>,
    /// Meridian nodes on the tread, ordered by y.
    pub tread_meridian: Vec<usize>,
    /// Meridian nodes on the symmetry plane.
    pub symmetry_meridian: Vec<usize>,
    /// Meridian nodes on the journal surface (r = journal radius).
    pub bearing_meridian: Vec<usize>,
    /// Added to node indices (see [`Self::shifted`]).
    pub node_offset: usize,
}

impl WheelTopology {
    /// Global node of meridian node `m` at angle index `k`.
    pub fn node(&self, k: usize, m: usize) -> usize {
        self.node_offset + k * self.meridian.len() + m
    }

    /// Index of θ = 0 in [`Self::thetas`].
    pub fn contact_angle_index(&self) -> usize {
        self.thetas
            .iter()
            .position(|&t| t == 0.0)
            .expect("θ = 0 is always a node angle")
    }

    /// All nodes on the symmetry plane (their lateral DOF is fixed by the symmetry condition).
    pub fn symmetry_plane_nodes(&self) -> Vec<usize> {
        self.ring_nodes(&self.symmetry_meridian)
    }

    /// All nodes on the journal (axle-box bearing seat) surface.
    pub fn bearing_nodes(&self) -> Vec<usize> {
        self.ring_nodes(&self.bearing_meridian)
    }

    /// Tread nodes with |θ| ≤ `half_angle_rad`, grouped by angle (ascending), each group
    /// ordered by y.
    pub fn tread_nodes_near_contact(&self, half_angle_rad: f64) -> Vec<usize> {
        let mut out = Vec::new();
        for (k, &t) in self.thetas.iter().enumerate() {
            if t.abs() <= half_angle_rad {
                out.extend(self.tread_meridian.iter().map(|&m| self.node(k, m)));
            }
        }
        out
    }

    /// The tread node at the nominal contact point (0, 0, −R).
    pub fn contact_node(&self) -> usize {
        let m = *self
            .tread_meridian
            .iter()
            .find(|&&m| self.meridian[m][0] == 0.0)
            .expect("y = 0 is always a node line of the tread");
        self.node(self.contact_angle_index(), m)
    }

    /// The same topology with node indices shifted (after `Mesh::append`).
    pub fn shifted(&self, node_offset: usize) -> Self {
        WheelTopology {
            node_offset,
            ..self.clone()
        }
    }

    fn ring_nodes(&self, meridian: &[usize]) -> Vec<usize> {
        (0..self.thetas.len())
            .flat_map(|k| meridian.iter().map(move |&m| (k, m)))
            .map(|(k, m)| self.node(k, m))
            .collect()
    }
}

fn bad(name: &'static str, value: f64, reason: &'static str) -> MeshError {
    MeshError::InvalidParameter {
        name,
        value,
        reason,
    }
}

impl WheelParams {
    fn blocks(&self) -> Vec<Block> {
        let y_sym = -self.symmetry_plane_distance_m;
        let mut b = vec![
            Block {
                y: [y_sym, self.journal_y_m[0]],
                r: [self.bore_radius_m, self.axle_radius_m],
            },
            Block {
                y: self.journal_y_m,
                r: [self.bore_radius_m, self.journal_radius_m],
            },
            Block {
                y: self.hub_y_m,
                r: [self.axle_radius_m, self.hub_radius_m],
            },
            Block {
                y: self.web_y_m,
                r: [self.hub_radius_m, self.rim_inner_radius_m],
            },
            Block {
                y: [self.rim_y_start_m, self.rim_y_end_m],
                r: [self.rim_inner_radius_m, self.radius_m],
            },
        ];
        if let Some(d) = self.brake_disc {
            b.push(Block {
                y: [d.y_start_m, d.y_end_m],
                r: [self.axle_radius_m, d.outer_radius_m],
            });
        }
        b
    }

    fn validate(&self) -> Result<(), MeshError> {
        let p = self;
        let pos = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(name, v, "must be finite and > 0"))
            }
        };
        pos("radius_m", p.radius_m)?;
        pos("bore_radius_m", p.bore_radius_m)?;
        pos("axial_size_m", p.axial_size_m)?;
        pos("radial_size_m", p.radial_size_m)?;
        pos("contact_size_m", p.contact_size_m)?;
        pos("contact_half_width_m", p.contact_half_width_m)?;
        pos("symmetry_plane_distance_m", p.symmetry_plane_distance_m)?;
        if !(p.conicity.is_finite() && p.conicity.abs() < 0.2) {
            return Err(bad("conicity", p.conicity, "must be |c| < 0.2"));
        }
        let radii_ok = p.bore_radius_m < p.journal_radius_m
            && p.journal_radius_m <= p.axle_radius_m
            && p.axle_radius_m < p.hub_radius_m
            && p.hub_radius_m < p.rim_inner_radius_m
            && p.rim_inner_radius_m
                < p.radius_m - p.conicity.abs() * p.rim_y_end_m.abs().max(p.rim_y_start_m.abs());
        if !radii_ok {
            return Err(bad(
                "rim_inner_radius_m",
                p.rim_inner_radius_m,
                "need bore < journal <= axle < hub < rim inner < tread radius",
            ));
        }
        let y_sym = -p.symmetry_plane_distance_m;
        let ys_ok = y_sym < p.hub_y_m[0]
            && p.hub_y_m[0] <= p.rim_y_start_m
            && p.rim_y_start_m <= p.web_y_m[0]
            && p.web_y_m[0] < p.web_y_m[1]
            && p.web_y_m[1] <= p.rim_y_end_m
            && p.rim_y_start_m < 0.0
            && p.rim_y_end_m > 0.0
            && p.hub_y_m[1] < p.journal_y_m[0]
            && p.journal_y_m[0] < p.journal_y_m[1];
        if !ys_ok {
            return Err(bad(
                "hub_y_m",
                p.hub_y_m[0],
                "need symmetry plane < hub start <= rim start < 0 < rim end, web inside the rim and hub, hub end < journal start < journal end",
            ));
        }
        if p.web_y_m[0] < p.hub_y_m[0] || p.web_y_m[1] > p.hub_y_m[1] {
            return Err(bad(
                "web_y_m",
                p.web_y_m[0],
                "the web must lie within the hub's y range",
            ));
        }
        if p.web_bend_m != 0.0 {
            let (a, b) = (p.rim_y_start_m, p.rim_y_end_m);
            let [w0, w1] = p.web_y_m;
            let d = p.web_bend_m;
            if !(d.is_finite() && a < w0 && w1 < b && a < w0 + d && w1 + d < b) {
                return Err(bad(
                    "web_bend_m",
                    d,
                    "a bent web's faces at the hub and at the rim must lie strictly inside the rim's faces",
                ));
            }
        }
        if let Some(d) = p.brake_disc {
            if !(d.y_start_m > y_sym && d.y_end_m > d.y_start_m && d.y_end_m < p.hub_y_m[0]) {
                return Err(bad(
                    "brake_disc.y_start_m",
                    d.y_start_m,
                    "the disc must lie between the symmetry plane and the hub",
                ));
            }
            if !(d.outer_radius_m > p.axle_radius_m && d.outer_radius_m.is_finite()) {
                return Err(bad(
                    "brake_disc.outer_radius_m",
                    d.outer_radius_m,
                    "must exceed the axle radius",
                ));
            }
        }
        if p.circumferential_divisions < 8 {
            return Err(bad(
                "circumferential_divisions",
                p.circumferential_divisions as f64,
                "need at least 8",
            ));
        }
        Ok(())
    }

    /// Exact volume of revolution of the meridian (m³): 2π ∫∫ r dA (Pappus–Guldinus).
    pub fn exact_volume_m3(&self) -> f64 {
        self.meridian_first_moment_m3() * 2.0 * std::f64::consts::PI
    }

    /// ∫∫ r dA over the meridian (m³), exact: blocks are rectangles except the rim, whose top
    /// r_t(y) = R − c y is linear, so ∫ (r_t² − r_i²)/2 dy is integrated exactly (Simpson).
    fn meridian_first_moment_m3(&self) -> f64 {
        let mut s = 0.0;
        for b in self.blocks() {
            if b.r[1] == self.radius_m && b.y == [self.rim_y_start_m, self.rim_y_end_m] {
                let f =
                    |y: f64| 0.5 * ((self.radius_m - self.conicity * y).powi(2) - b.r[0].powi(2));
                let (a, c) = (b.y[0], b.y[1]);
                s += (c - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + c)) + f(c));
            } else {
                s += 0.5 * (b.r[1].powi(2) - b.r[0].powi(2)) * (b.y[1] - b.y[0]);
            }
        }
        s
    }
}

/// Meshes the wheel and half axle (elements of [`Part::Wheel`], material index `material`).
///
/// Phases: the graded axial and radial grid lines (`meridian_grid`), the meridian cells
/// inside the blocks (`meridian_cells`), the graded angles (`wheel_angles`), the sweep
/// of the meridian around the axle (`sweep_meridian`) and the surfaces
/// (`wheel_topology`).
pub fn wheel(p: &WheelParams, material: usize) -> Result<(Mesh, WheelTopology), MeshError> {
    p.validate()?;
    let blocks = p.blocks();
    let (ys, rs) = meridian_grid(p, &blocks)?;
    let (meridian, quads) = meridian_cells(p, &blocks, &ys, &rs);
    let thetas = wheel_angles(p)?;
    let (nt, nm) = (thetas.len(), meridian.len());
    if nt.saturating_mul(nm) > p.max_nodes {
        return Err(MeshError::TooLarge {
            nodes: nt.saturating_mul(nm),
            layers: nt,
            per_layer: nm,
            limit: p.max_nodes,
        });
    }
    let mesh = sweep_meridian(&meridian, &quads, &thetas, material);
    Ok((mesh, wheel_topology(p, meridian, thetas)))
}

/// The tensor grid lines of the meridian: axial `y` (m, from the symmetry plane to the
/// journal's end) and radial `r` (m, from the bore to the tread), graded through the blocks'
/// bounds, fine at the contact and through the web.
fn meridian_grid(p: &WheelParams, blocks: &[Block]) -> Result<(Vec<f64>, Vec<f64>), MeshError> {
    let cw = p.contact_half_width_m;
    let hc = p.contact_size_m;
    let mut y_bps: Vec<f64> = blocks.iter().flat_map(|b| b.y).collect();
    y_bps.push(0.0);
    let y_sym = -p.symmetry_plane_distance_m;
    let mut spec = GradingSpec::new(y_sym, p.journal_y_m[1], p.axial_size_m);
    spec.breakpoints_m = y_bps;
    spec.max_ratio = 1.5;
    spec.zones.push(FineZone {
        start_m: -cw,
        end_m: cw,
        size_m: hc,
    });
    spec.zones.push(FineZone {
        start_m: p.web_y_m[0],
        end_m: p.web_y_m[1],
        size_m: (p.web_y_m[1] - p.web_y_m[0]) / p.web_layers.max(1) as f64,
    });
    let ys = grade(&spec)?;
    let r_bps: Vec<f64> = blocks.iter().flat_map(|b| b.r).collect();
    let mut spec = GradingSpec::new(p.bore_radius_m, p.radius_m, p.radial_size_m);
    spec.breakpoints_m = r_bps;
    spec.max_ratio = 1.5;
    spec.zones.push(FineZone {
        start_m: p.radius_m - cw,
        end_m: p.radius_m,
        size_m: hc,
    });
    if p.web_bend_m != 0.0 {
        // The bent web's mid-plane is resolved by at least 8 rows of elements.
        spec.zones.push(FineZone {
            start_m: p.hub_radius_m,
            end_m: p.rim_inner_radius_m,
            size_m: (p.rim_inner_radius_m - p.hub_radius_m) / 8.0,
        });
    }
    let rs = grade(&spec)?;
    Ok((ys, rs))
}

/// The meridian's used nodes `(y, r)` (m; rim nodes mapped radially onto the conical
/// tread) and its cells (four node indices each): the grid cells `(ys, rs)` whose centres
/// lie inside a block.
fn meridian_cells(
    p: &WheelParams,
    blocks: &[Block],
    ys: &[f64],
    rs: &[f64],
) -> (Vec<[f64; 2]>, Vec<[usize; 4]>) {
    let (ny, nr) = (ys.len(), rs.len());
    let inside = |yc: f64, rc: f64| {
        blocks
            .iter()
            .any(|b| yc > b.y[0] && yc < b.y[1] && rc > b.r[0] && rc < b.r[1])
    };
    let mut used = vec![usize::MAX; ny * nr];
    let mut meridian: Vec<[f64; 2]> = Vec::new();
    let mut quads: Vec<[usize; 4]> = Vec::new();
    let r_in = p.rim_inner_radius_m;
    let map_r = |y: f64, r: f64| -> f64 {
        if r > r_in {
            let rt = p.radius_m - p.conicity * y;
            r_in + (rt - r_in) * (r - r_in) / (p.radius_m - r_in)
        } else {
            r
        }
    };
    for b in 0..nr - 1 {
        for a in 0..ny - 1 {
            let (yc, rc) = (0.5 * (ys[a] + ys[a + 1]), 0.5 * (rs[b] + rs[b + 1]));
            if !inside(yc, rc) {
                continue;
            }
            let corners = [(a, b), (a + 1, b), (a + 1, b + 1), (a, b + 1)];
            let mut q = [0; 4];
            for (c, &(i, j)) in corners.iter().enumerate() {
                let g = j * ny + i;
                if used[g] == usize::MAX {
                    used[g] = meridian.len();
                    meridian.push([bent_y(p, ys[i], rs[j]), map_r(ys[i], rs[j])]);
                }
                q[c] = used[g];
            }
            quads.push(q);
        }
    }
    (meridian, quads)
}

/// The axial position (m) of the meridian grid point `(y, r)` (grid coordinates, before the
/// rim's cone map) once the web is bent by [`WheelParams::web_bend_m`]: in the web (hub radius < r <
/// rim inner radius) the web's mid-plane shift `bend (1 − cos πt)/2`, a shear that keeps the
/// axial thickness of every row of cells; in the rim a piecewise-linear remap of its y lines
/// that takes the web's faces to their bent positions at the rim's inner radius, keeps the
/// rim's faces, and fades linearly to none at the tread (the tread's nodes, and with them the
/// contact zone, do not move). Rows keep their order, so no cell turns over, and the rim's
/// region, hence ∫∫ r dA of the meridian, is unchanged. `y` itself for a straight web.
fn bent_y(p: &WheelParams, y: f64, r: f64) -> f64 {
    let d = p.web_bend_m;
    if d == 0.0 {
        return y;
    }
    let (rh, ri) = (p.hub_radius_m, p.rim_inner_radius_m);
    let [w0, w1] = p.web_y_m;
    let (a, b) = (p.rim_y_start_m, p.rim_y_end_m);
    if r >= ri && y >= a && y <= b {
        let remap = if y <= w0 {
            d * (y - a) / (w0 - a)
        } else if y <= w1 {
            d
        } else {
            d * (b - y) / (b - w1)
        };
        y + remap * (p.radius_m - r) / (p.radius_m - ri)
    } else if r > rh && r < ri && y >= w0 && y <= w1 {
        let t = (r - rh) / (ri - rh);
        y + d * 0.5 * (1.0 - (std::f64::consts::PI * t).cos())
    } else {
        y
    }
}

/// The node angles θ (rad) in (−π, π]: arc length at the radius graded, fine near the
/// contact point θ = 0.
fn wheel_angles(p: &WheelParams) -> Result<Vec<f64>, MeshError> {
    let cw = p.contact_half_width_m;
    let circ = 2.0 * std::f64::consts::PI * p.radius_m;
    let mut spec = GradingSpec::new(
        -0.5 * circ,
        0.5 * circ,
        circ / p.circumferential_divisions as f64,
    );
    spec.breakpoints_m = vec![0.0];
    spec.zones.push(FineZone {
        start_m: -cw,
        end_m: cw,
        size_m: p.contact_size_m,
    });
    let s = grade(&spec)?;
    // Drop −πR (it coincides with +πR).
    Ok(s[1..].iter().map(|v| v / p.radius_m).collect())
}

/// The meridian swept around the axle: one layer of nodes per angle in `thetas` and one
/// ring of hexahedra per meridian cell (material index `material`).
fn sweep_meridian(
    meridian: &[[f64; 2]],
    quads: &[[usize; 4]],
    thetas: &[f64],
    material: usize,
) -> Mesh {
    let (nt, nm) = (thetas.len(), meridian.len());
    let mut mesh = Mesh {
        nodes: Vec::with_capacity(nt * nm),
        elements: Vec::with_capacity(nt * quads.len()),
    };
    for &t in thetas {
        let (sn, cs) = t.sin_cos();
        mesh.nodes
            .extend(meridian.iter().map(|&[y, r]| [r * sn, y, -r * cs]));
    }
    for k in 0..nt {
        let (o0, o1) = (k * nm, ((k + 1) % nt) * nm);
        for q in quads {
            // ζ runs towards decreasing θ so that det J > 0 (see the module docs).
            mesh.elements.push(Hex8 {
                nodes: [
                    o1 + q[0],
                    o1 + q[1],
                    o1 + q[2],
                    o1 + q[3],
                    o0 + q[0],
                    o0 + q[1],
                    o0 + q[2],
                    o0 + q[3],
                ],
                material,
                part: Part::Wheel,
            });
        }
    }
    mesh
}

/// The wheel's topology: the meridian, the angles and the meridian nodes of the tread
/// (sorted by y), the symmetry plane and the bearing seat.
fn wheel_topology(p: &WheelParams, meridian: Vec<[f64; 2]>, thetas: Vec<f64>) -> WheelTopology {
    let nm = meridian.len();
    let y_sym = -p.symmetry_plane_distance_m;
    let r_top = |y: f64| p.radius_m - p.conicity * y;
    let mut tread: Vec<usize> = (0..nm)
        .filter(|&m| {
            let [y, r] = meridian[m];
            y >= p.rim_y_start_m && y <= p.rim_y_end_m && (r - r_top(y)).abs() < 1e-12
        })
        .collect();
    tread.sort_by(|&a, &b| meridian[a][0].total_cmp(&meridian[b][0]));
    let symmetry: Vec<usize> = (0..nm).filter(|&m| meridian[m][0] == y_sym).collect();
    let bearing: Vec<usize> = (0..nm)
        .filter(|&m| {
            let [y, r] = meridian[m];
            y >= p.journal_y_m[0] && y <= p.journal_y_m[1] && r == p.journal_radius_m
        })
        .collect();
    WheelTopology {
        meridian,
        thetas,
        tread_meridian: tread,
        symmetry_meridian: symmetry,
        bearing_meridian: bearing,
        node_offset: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::{wheel, Part, WheelParams, WheelTopology};
    #[test]
    fn volume_matches_pappus_and_mass_in_range() {
        let p = WheelParams::default();
        let (m, t) = wheel(&p, 0).unwrap();
        let v = m.part_volume(Part::Wheel);
        let v_exact = p.exact_volume_m3();
        // Faceted solid: exactly Σ sin Δθ_k / 2π of the solid of revolution.
        let mut ts = t.thetas.clone();
        ts.insert(0, ts[ts.len() - 1] - 2.0 * std::f64::consts::PI);
        let factor: f64 =
            ts.windows(2).map(|w| (w[1] - w[0]).sin()).sum::<f64>() / (2.0 * std::f64::consts::PI);
        let dmax = ts.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        eprintln!(
            "wheel: {} nodes, {} hex, {} angles; V {:.6} m3 vs Pappus {:.6} (rel {:.2e}, chord factor {:.6}); mass {:.1} kg",
            m.nodes.len(),
            m.elements.len(),
            t.thetas.len(),
            v,
            v_exact,
            v / v_exact - 1.0,
            factor,
            v * 7800.0
        );
        assert!((v / (v_exact * factor) - 1.0).abs() < 1e-10);
        assert!((1.0 - v / v_exact) <= dmax * dmax / 6.0 * 1.0001);
        let mass = v * 7800.0;
        assert!(mass > 600.0 && mass < 900.0, "{mass}");
        assert!(m.check_jacobians().unwrap() > 0.0);
        // Web layers.
        let web_lines: std::collections::BTreeSet<u64> = t
            .meridian
            .iter()
            .filter(|q| {
                q[0] >= p.web_y_m[0] - 1e-12
                    && q[0] <= p.web_y_m[1] + 1e-12
                    && q[1] > 0.2
                    && q[1] < 0.3
            })
            .map(|q| q[0].to_bits())
            .collect();
        assert!(
            web_lines.len() > p.web_layers,
            "{} node lines through the web",
            web_lines.len()
        );
    }

    #[test]
    fn without_disc_mass_is_the_disc_less() {
        // Independent check of the blocks: hand-computed ring volumes (π (r1² − r0²) Δy).
        use std::f64::consts::PI;
        let p = WheelParams::default();
        let q = WheelParams {
            brake_disc: None,
            ..p.clone()
        };
        let disc = PI * (0.32f64.powi(2) - 0.095f64.powi(2)) * 0.06;
        assert!((p.exact_volume_m3() - q.exact_volume_m3() - disc).abs() < 1e-12);
        let hand = PI * (0.095f64.powi(2) - 0.03f64.powi(2)) * 0.90
            + PI * (0.065f64.powi(2) - 0.03f64.powi(2)) * 0.18
            + PI * (0.15f64.powi(2) - 0.095f64.powi(2)) * 0.185
            + PI * (0.39f64.powi(2) - 0.15f64.powi(2)) * 0.03
            // Rim: ∫ π (r_t(y)² − r_i²) dy with r_t = 0.46 − y/40 over [−0.07, 0.065].
            + PI * ((-(0.46 - 0.065 / 40.0f64).powi(3) + (0.46 + 0.07 / 40.0f64).powi(3)) * 40.0 / 3.0
                - 0.39f64.powi(2) * 0.135);
        assert!((q.exact_volume_m3() / hand - 1.0).abs() < 1e-12);
    }

    #[test]
    fn topology_surfaces() {
        let p = WheelParams::default();
        let (m, t) = wheel(&p, 0).unwrap();
        let c = m.nodes[t.contact_node()];
        assert!(c[0].abs() < 1e-15 && c[1] == 0.0 && (c[2] + 0.46).abs() < 1e-15);
        for n in t.symmetry_plane_nodes() {
            assert_eq!(m.nodes[n][1], -0.75);
        }
        assert!(!t.symmetry_meridian.is_empty());
        for n in t.bearing_nodes() {
            let [x, y, z] = m.nodes[n];
            assert!(((x * x + z * z).sqrt() - 0.065).abs() < 1e-12 && (0.15..=0.33).contains(&y));
        }
        // Tread: cone r = R − y/40 and fine near the contact.
        let near = t.tread_nodes_near_contact(0.03 / 0.46);
        assert!(!near.is_empty());
        for &n in &near {
            let [x, y, z] = m.nodes[n];
            assert!(((x * x + z * z).sqrt() - (0.46 - y / 40.0)).abs() < 1e-12);
        }
        let k0 = t.contact_angle_index();
        assert!((t.thetas[k0 + 1] - t.thetas[k0]) * 0.46 <= p.contact_size_m * 1.000001);
        let tr: Vec<f64> = t.tread_meridian.iter().map(|&m| t.meridian[m][0]).collect();
        for w in tr.windows(2) {
            if w[0] >= -0.03 && w[1] <= 0.03 {
                assert!(w[1] - w[0] <= p.contact_size_m * 1.000001);
            }
        }
        assert_eq!(t.shifted(5).node(2, 3), t.node(2, 3) + 5);
    }

    /// A bent web: every element valid, the volume that of the straight web (the shear keeps
    /// each row's axial width; the faceted solid is Σ sin Δθ / 2π of Pappus), the tread's
    /// nodes where the straight wheel has them, and the web's mid-plane shifted by the bend
    /// at the rim and by half of it half way up.
    #[test]
    fn a_bent_web_keeps_the_volume_and_the_tread() {
        let straight = WheelParams::default();
        let bent = WheelParams {
            web_bend_m: 0.04,
            ..straight.clone()
        };
        let (ms, ts) = wheel(&straight, 0).unwrap();
        let (mb, tb) = wheel(&bent, 0).unwrap();
        assert!(mb.check_jacobians().unwrap() > 0.0);
        assert_eq!(bent.exact_volume_m3(), straight.exact_volume_m3());
        let mut th = tb.thetas.clone();
        th.insert(0, th[th.len() - 1] - 2.0 * std::f64::consts::PI);
        let factor: f64 =
            th.windows(2).map(|w| (w[1] - w[0]).sin()).sum::<f64>() / (2.0 * std::f64::consts::PI);
        let v = mb.part_volume(Part::Wheel);
        assert!(
            (v / (bent.exact_volume_m3() * factor) - 1.0).abs() < 1e-10,
            "{v}"
        );
        assert!(ms.part_volume(Part::Wheel) > 0.0);
        let tread = |t: &WheelTopology| -> Vec<[f64; 2]> {
            t.tread_meridian.iter().map(|&m| t.meridian[m]).collect()
        };
        assert_eq!(tread(&ts), tread(&tb));
        let mid = |r: f64| {
            let ys: Vec<f64> = tb
                .meridian
                .iter()
                .filter(|q| (q[1] - r).abs() < 1e-12 && q[0].abs() < 0.2)
                .map(|q| q[0])
                .collect();
            let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (0.5 * (lo + hi), hi - lo)
        };
        let s = |r: f64| 0.5 * (1.0 - (std::f64::consts::PI * (r - 0.15) / 0.24).cos());
        let rows: std::collections::BTreeSet<u64> = tb
            .meridian
            .iter()
            .filter(|q| q[1] > 0.15 && q[1] < 0.39 && q[0].abs() < 0.2)
            .map(|q| q[1].to_bits())
            .collect();
        assert!(rows.len() >= 7, "{} rows in the web", rows.len());
        for r in rows.into_iter().map(f64::from_bits) {
            let (m, t) = mid(r);
            assert!((t - 0.03).abs() < 1e-12, "{r}: {t}");
            assert!((m - (-0.03 + 0.04 * s(r))).abs() < 1e-12, "{r}: {m}");
        }
        // Out of the rim at the rim: refused.
        let out = WheelParams {
            web_bend_m: 0.09,
            ..straight
        };
        assert!(wheel(&out, 0).is_err());
    }

    #[test]
    fn bad_params_are_errors() {
        let bad = |p: WheelParams| wheel(&p, 0).is_err();
        assert!(bad(WheelParams {
            bore_radius_m: 0.0,
            ..Default::default()
        }));
        assert!(bad(WheelParams {
            rim_inner_radius_m: 0.47,
            ..Default::default()
        }));
        assert!(bad(WheelParams {
            circumferential_divisions: 4,
            ..Default::default()
        }));
        assert!(bad(WheelParams {
            web_y_m: [-0.2, -0.1],
            ..Default::default()
        }));
    }
}
