//! A half sleeper (one rail seat) as a solid rectangular block of 8-node hexahedra.
//!
//! Model: a monoblock concrete sleeper cut at the track centre line, idealised as a
//! rectangular block (the NS90's trapezoidal shape and the rail-seat inclination are not
//! modelled). Frame: x along the rail, y lateral (rail centre at y = 0, track centre towards
//! −y), z up with z = 0 at the rail-foot underside. The block spans
//! x ∈ [x_c − w/2, x_c + w/2], y ∈ [−a, L − a] (a = rail-seat offset from the sleeper's
//! track-centre end, L = length), z ∈ [−t_pad − H, −t_pad].
//! Default 1.25 × 0.25 × 0.2 m: V = 0.0625 m³, 156.25 kg at 2500 kg/m³
//! (docs/theory.md §3.1: about 130–150 kg for the real, tapered half sleeper).
//!
//! The top face (fastening springs, by interpolation in its quads) and the bottom face
//! (ballast springs, by area weights) are returned as quads with their areas.

use super::grading::{grade, GradingSpec};
use super::{Hex8, Mesh, MeshError, Part};

/// Parameters of the half sleeper (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct SleeperParams {
    /// Length across the track, L (m).
    pub length_m: f64,
    /// Width along the rail, w (m).
    pub width_m: f64,
    /// Height, H (m).
    pub height_m: f64,
    /// Lateral distance from the sleeper's track-centre end to the rail seat centre, a (m).
    pub rail_seat_offset_m: f64,
    /// Gap between the rail-foot underside (z = 0) and the sleeper top (m): the pad.
    pub pad_thickness_m: f64,
    /// x of the sleeper centre line (m).
    pub centre_x_m: f64,
    /// Elements across the track (along y): the maximum size is L / n.
    pub n_length: usize,
    /// Elements along the rail (along x).
    pub n_width: usize,
    /// Elements through the height.
    pub n_height: usize,
    /// Extra lateral positions (m) that must be node lines (e.g. the rail-foot edges ±0.07).
    pub y_node_lines_m: Vec<f64>,
}

impl Default for SleeperParams {
    fn default() -> Self {
        SleeperParams {
            length_m: 1.25,
            width_m: 0.25,
            height_m: 0.2,
            rail_seat_offset_m: 0.75,
            pad_thickness_m: 0.01,
            centre_x_m: 0.0,
            n_length: 25,
            n_width: 5,
            n_height: 4,
            y_node_lines_m: Vec::new(),
        }
    }
}

/// A quadrilateral face of the block: nodes counter-clockwise seen from outside, and its area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceQuad {
    /// Global node indices; natural coordinates (ξ along x, η along y) of the nodes are
    /// (−1,−1), (1,−1), (1,1), (−1,1) for the top face.
    pub nodes: [usize; 4],
    /// Area (m²).
    pub area_m2: f64,
}

/// Topology of a meshed half sleeper.
#[derive(Debug, Clone, PartialEq)]
pub struct SleeperTopology {
    /// Node x positions (m).
    pub xs: Vec<f64>,
    /// Node y positions (m).
    pub ys: Vec<f64>,
    /// Node z positions (m), bottom to top.
    pub zs: Vec<f64>,
    /// Top-face quads, index `j · (xs.len() − 1) + i` for the cell [xs_i, xs_{i+1}] × [ys_j, ys_{j+1}].
    pub top_face: Vec<FaceQuad>,
    /// Bottom-face quads (same cell indexing; nodes counter-clockwise seen from below).
    pub bottom_face: Vec<FaceQuad>,
    /// Added to node indices (see [`Self::shifted`]).
    pub node_offset: usize,
}

impl SleeperTopology {
    /// Global node at grid position (i along x, j along y, k along z).
    pub fn node(&self, i: usize, j: usize, k: usize) -> usize {
        self.node_offset + (k * self.ys.len() + j) * self.xs.len() + i
    }

    /// The top-face quad (index into [`Self::top_face`]) below the point (x, y) and its natural
    /// coordinates (ξ, η) ∈ [−1, 1]²; `None` outside the top face.
    pub fn top_quad_at(&self, x: f64, y: f64) -> Option<(usize, [f64; 2])> {
        let (i, xi) = cell(&self.xs, x)?;
        let (j, eta) = cell(&self.ys, y)?;
        Some((j * (self.xs.len() - 1) + i, [xi, eta]))
    }

    /// Lumped bottom-face areas: each node gets a quarter of the area of every bottom quad it
    /// belongs to (m²); the weights sum to the bottom area.
    pub fn bottom_node_areas(&self) -> Vec<(usize, f64)> {
        let mut out: Vec<(usize, f64)> = Vec::new();
        let mut pos = std::collections::HashMap::new();
        for q in &self.bottom_face {
            for &n in &q.nodes {
                let k = *pos.entry(n).or_insert_with(|| {
                    out.push((n, 0.0));
                    out.len() - 1
                });
                out[k].1 += 0.25 * q.area_m2;
            }
        }
        out
    }

    /// The same topology with node indices shifted by `node_offset` (after `Mesh::append`).
    pub fn shifted(&self, node_offset: usize) -> Self {
        let d = node_offset as isize - self.node_offset as isize;
        let sh = |f: &FaceQuad| FaceQuad {
            nodes: f.nodes.map(|n| (n as isize + d) as usize),
            area_m2: f.area_m2,
        };
        SleeperTopology {
            top_face: self.top_face.iter().map(sh).collect(),
            bottom_face: self.bottom_face.iter().map(sh).collect(),
            node_offset,
            ..self.clone()
        }
    }
}

/// Interval index and natural coordinate of `v` in the sorted grid `g`.
fn cell(g: &[f64], v: f64) -> Option<(usize, f64)> {
    let n = g.len();
    if !(v >= g[0] && v <= g[n - 1]) {
        return None;
    }
    let i = g.partition_point(|&a| a <= v).clamp(1, n - 1) - 1;
    Some((i, 2.0 * (v - g[i]) / (g[i + 1] - g[i]) - 1.0))
}

fn check_pos(name: &'static str, v: f64) -> Result<(), MeshError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(MeshError::InvalidParameter {
            name,
            value: v,
            reason: "must be finite and > 0",
        })
    }
}

/// Meshes a half sleeper (elements of [`Part::Sleeper`] with material index `material`):
/// the checked parameters, the grid lines (`sleeper_grid`), the hexahedra
/// (`sleeper_hexes`) and the top and bottom faces (`sleeper_faces`).
pub fn half_sleeper(
    p: &SleeperParams,
    material: usize,
) -> Result<(Mesh, SleeperTopology), MeshError> {
    check_sleeper(p)?;
    let [xs, ys, zs] = sleeper_grid(p)?;
    let grid = [xs.as_slice(), ys.as_slice(), zs.as_slice()];
    let mesh = sleeper_hexes(grid, material);
    let (top_face, bottom_face) = sleeper_faces(grid);
    Ok((
        mesh,
        SleeperTopology {
            xs,
            ys,
            zs,
            top_face,
            bottom_face,
            node_offset: 0,
        },
    ))
}

/// Dimensions finite and positive, pad thickness ≥ 0, offsets finite, at least one
/// element in each direction.
fn check_sleeper(p: &SleeperParams) -> Result<(), MeshError> {
    check_pos("length_m", p.length_m)?;
    check_pos("width_m", p.width_m)?;
    check_pos("height_m", p.height_m)?;
    if !(p.pad_thickness_m.is_finite() && p.pad_thickness_m >= 0.0) {
        return Err(MeshError::InvalidParameter {
            name: "pad_thickness_m",
            value: p.pad_thickness_m,
            reason: "must be finite and >= 0",
        });
    }
    if !(p.rail_seat_offset_m.is_finite() && p.centre_x_m.is_finite()) {
        return Err(MeshError::InvalidParameter {
            name: "rail_seat_offset_m",
            value: p.rail_seat_offset_m,
            reason: "must be finite (and centre_x_m too)",
        });
    }
    for (name, n) in [
        ("n_length", p.n_length),
        ("n_width", p.n_width),
        ("n_height", p.n_height),
    ] {
        if n == 0 {
            return Err(MeshError::InvalidParameter {
                name,
                value: 0.0,
                reason: "need at least one element",
            });
        }
    }
    Ok(())
}

/// The grid lines x (across the sleeper, uniform), y (along it, graded through the node
/// lines when given, else uniform) and z (uniform, top at the pad's underside), all in m.
fn sleeper_grid(p: &SleeperParams) -> Result<[Vec<f64>; 3], MeshError> {
    let uniform = |a: f64, b: f64, n: usize| -> Vec<f64> {
        (0..=n)
            .map(|k| {
                if k == n {
                    b
                } else {
                    a + (b - a) * k as f64 / n as f64
                }
            })
            .collect()
    };
    let x0 = p.centre_x_m - 0.5 * p.width_m;
    let xs = uniform(x0, x0 + p.width_m, p.n_width);
    let y0 = -p.rail_seat_offset_m;
    let y1 = y0 + p.length_m;
    let ys = if p.y_node_lines_m.is_empty() {
        uniform(y0, y1, p.n_length)
    } else {
        let mut spec = GradingSpec::new(y0, y1, p.length_m / p.n_length as f64);
        spec.breakpoints_m = p.y_node_lines_m.clone();
        spec.max_ratio = 2.0;
        grade(&spec)?
    };
    let z1 = -p.pad_thickness_m;
    let zs = uniform(z1 - p.height_m, z1, p.n_height);
    Ok([xs, ys, zs])
}

/// Index of node (i, j, k) of the grid with `nx × ny` nodes per layer.
fn grid_node(nx: usize, ny: usize) -> impl Fn(usize, usize, usize) -> usize {
    move |i, j, k| (k * ny + j) * nx + i
}

/// The nodes (x fastest, then y, then z) and hexahedra of the grid `[xs, ys, zs]`.
fn sleeper_hexes([xs, ys, zs]: [&[f64]; 3], material: usize) -> Mesh {
    let (nx, ny, nz) = (xs.len(), ys.len(), zs.len());
    let mut mesh = Mesh::default();
    for &z in zs {
        for &y in ys {
            for &x in xs {
                mesh.nodes.push([x, y, z]);
            }
        }
    }
    let id = grid_node(nx, ny);
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                mesh.elements.push(Hex8 {
                    nodes: [
                        id(i, j, k),
                        id(i + 1, j, k),
                        id(i + 1, j + 1, k),
                        id(i, j + 1, k),
                        id(i, j, k + 1),
                        id(i + 1, j, k + 1),
                        id(i + 1, j + 1, k + 1),
                        id(i, j + 1, k + 1),
                    ],
                    material,
                    part: Part::Sleeper,
                });
            }
        }
    }
    mesh
}

/// The top (pad side) and bottom (ballast side, outward normal down) faces of the grid
/// `[xs, ys, zs]`, with their areas (m²).
fn sleeper_faces([xs, ys, zs]: [&[f64]; 3]) -> (Vec<FaceQuad>, Vec<FaceQuad>) {
    let (nx, ny, nz) = (xs.len(), ys.len(), zs.len());
    let id = grid_node(nx, ny);
    let mut top_face = Vec::with_capacity((nx - 1) * (ny - 1));
    let mut bottom_face = Vec::with_capacity((nx - 1) * (ny - 1));
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let area = (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
            let t = nz - 1;
            top_face.push(FaceQuad {
                nodes: [
                    id(i, j, t),
                    id(i + 1, j, t),
                    id(i + 1, j + 1, t),
                    id(i, j + 1, t),
                ],
                area_m2: area,
            });
            bottom_face.push(FaceQuad {
                nodes: [
                    id(i, j, 0),
                    id(i, j + 1, 0),
                    id(i + 1, j + 1, 0),
                    id(i + 1, j, 0),
                ],
                area_m2: area,
            });
        }
    }
    (top_face, bottom_face)
}

#[cfg(test)]
mod tests {
    use super::{half_sleeper, FaceQuad, Part, SleeperParams};
    #[test]
    fn default_block_volume_mass_and_faces() {
        let (m, t) = half_sleeper(&SleeperParams::default(), 1).unwrap();
        let v = m.part_volume(Part::Sleeper);
        // 1.25 × 0.25 × 0.2 = 0.0625 m³; × 2500 kg/m³ = 156.25 kg.
        assert!((v - 0.0625).abs() < 1e-14);
        assert!((v * 2500.0 - 156.25).abs() < 1e-10);
        assert!(m.check_jacobians().unwrap() > 0.0);
        let top: f64 = t.top_face.iter().map(|q| q.area_m2).sum();
        let bot: f64 = t.bottom_node_areas().iter().map(|w| w.1).sum();
        assert!((top - 0.3125).abs() < 1e-14 && (bot - 0.3125).abs() < 1e-14);
        assert!(t
            .top_face
            .iter()
            .flat_map(|q| q.nodes)
            .all(|n| m.nodes[n][2] == -0.01));
        assert!(t
            .bottom_face
            .iter()
            .flat_map(|q| q.nodes)
            .all(|n| (m.nodes[n][2] + 0.21).abs() < 1e-15));
        // Face orientation: outward normals +z (top) and −z (bottom).
        let normal_z = |q: &FaceQuad| {
            let p = q.nodes.map(|n| m.nodes[n]);
            (p[1][0] - p[0][0]) * (p[2][1] - p[1][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[1][0])
        };
        assert!(t.top_face.iter().all(|q| normal_z(q) > 0.0));
        assert!(t.bottom_face.iter().all(|q| normal_z(q) < 0.0));
        // Extent: y from −0.75 to 0.5, x ±0.125.
        assert_eq!((t.ys[0], *t.ys.last().unwrap()), (-0.75, 0.5));
        assert_eq!((t.xs[0], *t.xs.last().unwrap()), (-0.125, 0.125));
    }

    #[test]
    fn top_quad_lookup_interpolates() {
        let p = SleeperParams {
            centre_x_m: 0.6,
            y_node_lines_m: vec![-0.07, 0.07],
            ..Default::default()
        };
        let (m, t) = half_sleeper(&p, 1).unwrap();
        assert!(t.ys.contains(&-0.07) && t.ys.contains(&0.07));
        for &(x, y) in &[(0.6, 0.0), (0.5, -0.7), (0.725, 0.5), (0.61, 0.0123)] {
            let (q, [xi, eta]) = t.top_quad_at(x, y).unwrap();
            let nodes = t.top_face[q].nodes;
            let nat = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
            let (mut px, mut py) = (0.0, 0.0);
            for k in 0..4 {
                let w = 0.25 * (1.0 + nat[k][0] * xi) * (1.0 + nat[k][1] * eta);
                px += w * m.nodes[nodes[k]][0];
                py += w * m.nodes[nodes[k]][1];
            }
            assert!((px - x).abs() < 1e-14 && (py - y).abs() < 1e-14);
        }
        assert!(t.top_quad_at(0.3, 0.0).is_none());
        let s = t.shifted(1000);
        assert_eq!(s.top_face[0].nodes[0], t.top_face[0].nodes[0] + 1000);
        assert_eq!(s.node(1, 2, 3), t.node(1, 2, 3) + 1000);
    }

    #[test]
    fn bad_params_are_errors() {
        let bad = |p: SleeperParams| half_sleeper(&p, 0).is_err();
        assert!(bad(SleeperParams {
            height_m: 0.0,
            ..Default::default()
        }));
        assert!(bad(SleeperParams {
            n_width: 0,
            ..Default::default()
        }));
        assert!(bad(SleeperParams {
            pad_thickness_m: -0.01,
            ..Default::default()
        }));
        assert!(bad(SleeperParams {
            y_node_lines_m: vec![0.6],
            ..Default::default()
        }));
    }
}
