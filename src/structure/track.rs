//! The track substructure: rail, half sleepers, railpads, rigid holds and ballast.
//!
//! - **Rail**: the UIC54 section mesh (inclined by `rail.inclination`) extruded through node
//!   planes graded from `mesh.element_length` down to `mesh.fine_element_length` around the
//!   solution zone, with node planes at every footprint-cell and held-strip edge.
//! - **Railpad** (per fastening, docs/theory.md §3.2): a `rows × columns` grid of spring-dampers,
//!   stiffness `k/(rows·columns)` each. Each grid spring acts on its footprint cell: it is
//!   spread over the rail-foot underside nodes of the cell in proportion to their tributary
//!   area (trapezoidal weights), each node tied to the sleeper-top point straight below it
//!   (bilinear interpolation on the top face). A uniform pad pressure is thus represented
//!   exactly, and the pad stiffness does not depend on the mesh.
//! - **Rigid holds**: the fastening model's [`HoldPattern`] fixes
//!   rail-foot underside DOFs to the ground, region by region (columns and rows are strips of
//!   physical width; their edges are node lines, so the held set is exact). Node-line regions
//!   fix the foot nodes of one node plane (a column line) or one foot node line within the
//!   footprint (a row line): a constraint of zero width, mesh dependent (`node_line`).
//! - **Elastic holds**: a region held elastically is tied to the ground in its direction by
//!   spring-dampers, the stiffness and damping per fastening spread over the region's nodes by
//!   tributary area (per bay of one sleeper spacing for the continuous region; evenly over the
//!   grid-point nodes; per held line, by tributary length along it, for node lines). As
//!   k → ∞ they approach the rigid hold of the same region.
//! - **Ballast**: per half sleeper, stiffness and damping in x, y, z spread over the
//!   bottom-face nodes by tributary area, to the ground.
//! - **Rail ends**: free, or absorbing by dashpots on the end faces (`track.ends`,
//!   [`super::ends`]).

use std::time::Instant;

use crate::fe::assembly::{assemble, AssemblyOptions, DofMap, FeMatrices, MassKind};
use crate::fe::material::IsotropicElastic;
use crate::fe::spring::Spring;
use crate::mesh::grading::{grade, FineZone, GradingSpec};
use crate::mesh::profile::SectionProperties;
use crate::mesh::rail::{extrude_rail, RailTopology};
use crate::mesh::section::{SectionMesh, SectionParams};
use crate::mesh::sleeper::{half_sleeper, SleeperParams, SleeperTopology};
use crate::mesh::Mesh;
use crate::model::{HoldPattern, Model, NodePlanes, RailEnds, RigidRegion};

use super::ends::end_dashpots;

use super::layout::{tributary_lengths, Layout, GEOMETRY_TOLERANCE};
use super::StructureError;

/// Material index of the rail in [`TrackStructure::materials`].
pub const RAIL_MATERIAL: usize = 0;
/// Material index of the sleepers.
pub(crate) const SLEEPER_MATERIAL: usize = 1;

/// What a spring represents (for energy shares and output).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpringKind {
    /// A railpad spring-damper (rail foot to sleeper).
    Fastening,
    /// A ballast spring-damper (sleeper to ground).
    Ballast,
    /// An elastic hold of the fastening (rail foot to ground, one direction).
    Hold,
    /// A dashpot of an absorbing rail end (end-face node to ground, damping only;
    /// [`super::ends`]).
    EndDashpot,
}

/// The track substructure, before assembly.
#[derive(Debug, Clone)]
pub struct TrackStructure {
    /// Nodes and hexahedra (rail first, then the sleepers).
    pub mesh: Mesh,
    /// Materials: [`RAIL_MATERIAL`], `SLEEPER_MATERIAL`.
    pub materials: Vec<IsotropicElastic>,
    /// Spring-dampers (railpads and ballast).
    pub springs: Vec<Spring>,
    /// Kind of each spring.
    pub spring_kinds: Vec<SpringKind>,
    /// Free/constrained DOFs (the rigid holds).
    pub dofmap: DofMap,
    /// Rail node/element maps.
    pub rail: RailTopology,
    /// Sleeper topologies (node indices global).
    pub sleepers: Vec<SleeperTopology>,
    /// Support layout.
    pub layout: Layout,
    /// Section properties of the (upright) rail section mesh.
    pub section_properties: SectionProperties,
    /// Mass matrix kind of the model.
    pub mass: MassKind,
}

impl TrackStructure {
    /// Builds the track substructure of a model: the rail section (`rail_section`),
    /// extruded over the graded node planes (`rail_planes`), the half sleepers
    /// (`add_sleepers`), the railpad, ballast and elastic-hold springs, and the held DOFs.
    pub fn build(m: &Model) -> Result<TrackStructure, StructureError> {
        let layout = Layout::new(m);
        let hold = m.fastening.hold_pattern();
        let (section, section_properties) = rail_section(m, &layout, &hold)?;
        let planes = rail_planes(m, &layout, &hold, &section)?;
        let (mut mesh, rail) = extrude_rail(&section, &planes, RAIL_MATERIAL)?;
        let sleepers = add_sleepers(m, &layout, &mut mesh)?;

        let mut springs = Vec::new();
        let mut spring_kinds = Vec::new();
        add_railpads(
            m,
            &layout,
            &mesh,
            &rail,
            &sleepers,
            &mut springs,
            &mut spring_kinds,
        )?;
        add_ballast(m, &sleepers, &mut springs, &mut spring_kinds);
        add_elastic_holds(
            &hold,
            &layout,
            m.track.sleeper_spacing,
            &rail,
            &mut springs,
            &mut spring_kinds,
        )?;

        if m.track.ends == RailEnds::Absorbing {
            let d = end_dashpots(
                &rail,
                &m.rail_material(),
                m.track.absorbing_layer_length,
                m.track.absorbing_layer_rate,
            );
            spring_kinds.extend(std::iter::repeat_n(SpringKind::EndDashpot, d.len()));
            springs.extend(d);
        }

        let held = held_dofs(&hold, &layout, &rail)?;
        let dofmap = DofMap::with_constraints(mesh.nodes.len(), &held)?;
        Ok(TrackStructure {
            mesh,
            materials: vec![m.rail_material(), m.sleeper_material()],
            springs,
            spring_kinds,
            dofmap,
            rail,
            sleepers,
            layout,
            section_properties,
            mass: super::mass_kind(m.mesh.mass),
        })
    }

    /// Assembles K, M, C over the free DOFs; returns them with the wall time (s).
    pub fn assemble(&self) -> Result<(FeMatrices, f64), StructureError> {
        let t = Instant::now();
        let mats = assemble(
            &self.mesh,
            &self.materials,
            &self.springs,
            &[],
            &self.dofmap,
            AssemblyOptions { mass: self.mass },
        )?;
        Ok((mats, t.elapsed().as_secs_f64()))
    }

    /// The damping matrix `C` alone (N·s/m, over the free DOFs): the nonzero values of
    /// [`Self::assemble`]'s `C`, without assembling the elements
    /// ([`crate::fe::assembly::assemble_damping`]).
    pub fn assemble_damping(
        &self,
    ) -> Result<faer::sparse::SparseColMat<usize, f64>, StructureError> {
        Ok(crate::fe::assembly::assemble_damping(
            &self.springs,
            self.mesh.nodes.len(),
            &self.dofmap,
        )?)
    }
}

/// The upright rail section's mesh parameters: the model's sizes, and foot node lines at the
/// fastenings' holds within the footprint and the rail foot.
fn section_params(m: &Model, layout: &Layout, hold: &HoldPattern) -> SectionParams {
    let foot_lines: Vec<f64> = layout
        .y_foot_lines(hold)
        .into_iter()
        .filter(|&y| {
            y > GEOMETRY_TOLERANCE
                && y < 0.5
                    * m.fastening
                        .footprint_width
                        .min(crate::mesh::profile::UIC54_FOOT_WIDTH_M)
                    - 1e-6
        })
        .collect();
    SectionParams {
        size_m: m.mesh.section_size,
        running_surface_size_m: m.mesh.head_size,
        foot_node_lines_m: foot_lines,
        inclination_rad: 0.0,
        ..SectionParams::default()
    }
}

/// The model's rail section mesh as bytes (node coordinates, quadrilaterals, foot and
/// running-surface node lists, inclination): what the modal cache keys a track by beside the
/// model's values, so that a change of the section mesher keys every model it changes apart
/// (and every key changes once, when this was added).
pub(crate) fn section_mesh_bytes(m: &Model) -> Result<Vec<u8>, StructureError> {
    let (section, _) = rail_section(m, &Layout::new(m), &m.fastening.hold_pattern())?;
    let mut b = Vec::with_capacity(16 * section.nodes.len() + 32 * section.quads.len() + 64);
    let mut put = |x: u64| b.extend_from_slice(&x.to_le_bytes());
    put(section.nodes.len() as u64);
    for p in &section.nodes {
        put(p[0].to_bits());
        put(p[1].to_bits());
    }
    put(section.quads.len() as u64);
    for q in &section.quads {
        q.iter().for_each(|&n| put(n as u64));
    }
    for list in [&section.foot_underside, &section.running_surface] {
        put(list.len() as u64);
        list.iter().for_each(|&n| put(n as u64));
    }
    put(section.inclination_rad.to_bits());
    Ok(b)
}

/// The inclined rail section (foot node lines at the fastenings' holds, within the
/// footprint and the rail foot) and the properties of the upright one.
fn rail_section(
    m: &Model,
    layout: &Layout,
    hold: &HoldPattern,
) -> Result<(SectionMesh, SectionProperties), StructureError> {
    let mut params = section_params(m, layout, hold);
    let upright = SectionMesh::uic54(&params)?;
    let section_properties = upright.properties();
    params.inclination_rad = m.rail.inclination.atan();
    let section = SectionMesh::uic54(&params)?;
    Ok((section, section_properties))
}

/// The rail's node planes along x (m): graded, fine in the fine zone, through the
/// breakpoints of the holds. A model too large to build is refused before grading or
/// allocating it, and again once the planes are known.
fn rail_planes(
    m: &Model,
    layout: &Layout,
    hold: &HoldPattern,
    section: &SectionMesh,
) -> Result<Vec<f64>, StructureError> {
    let [f0, f1] = layout.fine_zone;
    // The node planes along the rail are about the fine zone over its element length plus
    // the track over the coarse one; a half sleeper has (nx+1)(ny+3)(nz+1) nodes (two extra
    // y lines at the rail foot edges).
    let [sx, sy, sz] = m.mesh.sleeper_elements;
    let sleeper_nodes = ((sx + 1) * (sy + 3) * (sz + 1) * layout.sleepers.len()) as f64;
    let section_nodes = section.nodes.len() as f64;
    let size_hint = |planes: f64| {
        move || {
            format!(
                "rail {planes:.0} node planes (mesh.fine_element_length = {} m, mesh.element_length = {} m) x {section_nodes} section nodes (mesh.section_size = {} m, mesh.head_size = {} m), sleepers {sleeper_nodes} nodes (mesh.sleeper_elements = {:?}); coarsen these",
                m.mesh.fine_element_length,
                m.mesh.element_length,
                m.mesh.section_size,
                m.mesh.head_size,
                m.mesh.sleeper_elements
            )
        }
    };
    let planes_estimate =
        (f1 - f0) / m.mesh.fine_element_length + layout.length / m.mesh.element_length;
    super::check_size(
        "track",
        planes_estimate * section_nodes + sleeper_nodes,
        size_hint(planes_estimate),
    )?;
    let fine = FineZone {
        start_m: f0,
        end_m: f1,
        size_m: m.mesh.fine_element_length,
    };
    let coarse = GradingSpec::new(0.0, layout.length, m.mesh.element_length);
    let planes = match m.mesh.node_planes {
        NodePlanes::Graded => grade(&GradingSpec {
            zones: vec![fine],
            breakpoints_m: layout.x_breakpoints(hold),
            ..coarse
        })?,
        NodePlanes::Lattice => lattice_planes(&coarse, fine, &layout.x_breakpoints(hold))?,
    };
    let planes_n = planes.len() as f64;
    super::check_size(
        "track",
        planes_n * section_nodes + sleeper_nodes,
        size_hint(planes_n),
    )?;
    Ok(planes)
}

/// The node planes of [`NodePlanes::Lattice`] over `coarse`'s interval: the fine zone moved
/// out to the lattice `x = k·e` (`e = fine.size_m`; clipped to the rail), every plane inside
/// it on the lattice (the last element shorter only where the zone is clipped to a rail end off
/// the lattice), the parts outside graded as [`NodePlanes::Graded`] grades them through their
/// own breakpoints; breakpoints inside the zone are dropped.
fn lattice_planes(
    coarse: &GradingSpec,
    fine: FineZone,
    breakpoints: &[f64],
) -> Result<Vec<f64>, crate::mesh::MeshError> {
    let (x0, x1, e) = (coarse.start_m, coarse.end_m, fine.size_m);
    let tol = 1e-9 * e;
    let ka = ((fine.start_m - x0) / e + 1e-9).floor().max(0.0) as usize;
    let a = x0 + ka as f64 * e;
    let b = ((fine.end_m - x0) / e - 1e-9).ceil() * e + x0;
    let b = b.min(x1);
    let zone = FineZone {
        start_m: a,
        end_m: b,
        size_m: e,
    };
    let part = |lo: f64, hi: f64| {
        grade(&GradingSpec {
            zones: vec![zone],
            breakpoints_m: breakpoints
                .iter()
                .copied()
                .filter(|&x| x > lo + tol && x < hi - tol)
                .collect(),
            ..GradingSpec::new(lo, hi, coarse.coarse_size_m)
        })
    };
    let mut planes = if a > x0 + tol {
        let mut left = part(x0, a)?;
        left.pop();
        left
    } else {
        Vec::new()
    };
    let mut k = ka;
    loop {
        let x = x0 + k as f64 * e;
        if x >= b - tol {
            break;
        }
        planes.push(x);
        k += 1;
    }
    planes.push(b);
    if b < x1 - tol {
        planes.extend(part(b, x1)?.into_iter().skip(1));
    }
    Ok(planes)
}

/// Meshes the half sleepers of the layout (node lines at the rail seat's footprint edges)
/// and appends them to `mesh`; returns their topologies in `mesh`'s numbering.
fn add_sleepers(
    m: &Model,
    layout: &Layout,
    mesh: &mut Mesh,
) -> Result<Vec<SleeperTopology>, StructureError> {
    let mut sleepers = Vec::with_capacity(layout.sleepers.len());
    for &xs in &layout.sleepers {
        let [nx, ny, nz] = m.mesh.sleeper_elements;
        let half_foot = 0.5 * m.fastening.footprint_width;
        let (smesh, topo) = half_sleeper(
            &SleeperParams {
                length_m: m.sleeper.length,
                width_m: m.sleeper.width,
                height_m: m.sleeper.height,
                rail_seat_offset_m: m.sleeper.rail_seat,
                pad_thickness_m: m.fastening.pad_thickness,
                centre_x_m: xs,
                n_length: ny,
                n_width: nx,
                n_height: nz,
                y_node_lines_m: vec![-half_foot, half_foot],
            },
            SLEEPER_MATERIAL,
        )?;
        let offset = mesh.append(&smesh);
        sleepers.push(topo.shifted(offset));
    }
    Ok(sleepers)
}

/// Bilinear shape functions of a quad face at (ξ, η), node order (−1,−1), (1,−1), (1,1), (−1,1).
fn quad_shape(xi: f64, eta: f64) -> [f64; 4] {
    [
        0.25 * (1.0 - xi) * (1.0 - eta),
        0.25 * (1.0 + xi) * (1.0 - eta),
        0.25 * (1.0 + xi) * (1.0 + eta),
        0.25 * (1.0 - xi) * (1.0 + eta),
    ]
}

fn add_railpads(
    m: &Model,
    layout: &Layout,
    mesh: &Mesh,
    rail: &RailTopology,
    sleepers: &[SleeperTopology],
    springs: &mut Vec<Spring>,
    kinds: &mut Vec<SpringKind>,
) -> Result<(), StructureError> {
    let f = &m.fastening;
    let n_grid = (f.rows * f.columns) as f64;
    let (k, c) = (f.springs.stiffness(), f.springs.damping());
    let foot_s = &rail.section.foot_underside_s_m;
    for (s, &xs) in sleepers.iter().zip(&layout.sleepers) {
        for col in 0..layout.columns {
            let [xa, xb] = layout.column_cell(xs, col);
            let lx = tributary_lengths(&rail.planes_x_m, xa, xb);
            for row in 0..layout.rows {
                let [ya, yb] = layout.row_cell(row);
                let ly = tributary_lengths(foot_s, ya, yb);
                let cell_area = (xb - xa) * (yb - ya);
                let covered: f64 = lx.iter().sum::<f64>() * ly.iter().sum::<f64>();
                if (covered - cell_area).abs() > 1e-9 * cell_area.max(1e-12) + 1e-12 {
                    return Err(StructureError::CellNotCovered {
                        row,
                        column: col,
                        x_m: xs,
                        covered_m2: covered,
                        cell_m2: cell_area,
                    });
                }
                for (i, &wx) in lx.iter().enumerate().filter(|(_, &w)| w > 0.0) {
                    for (j, &wy) in ly.iter().enumerate().filter(|(_, &w)| w > 0.0) {
                        let share = wx * wy / cell_area;
                        let node = rail.node(i, rail.section.foot_underside[j]);
                        let [x, y, _] = mesh.nodes[node];
                        let (q, [xi, eta]) = s
                            .top_quad_at(x, y)
                            .ok_or(StructureError::FootOffSleeper { x_m: x, y_m: y })?;
                        let face = s.top_face[q].nodes;
                        let nq = quad_shape(xi, eta);
                        for d in 0..3 {
                            if k[d] == 0.0 && c[d] == 0.0 {
                                continue;
                            }
                            let side_b = face
                                .iter()
                                .zip(nq)
                                .filter(|(_, w)| w.abs() > 1e-14)
                                .map(|(&n, w)| (3 * n + d, w))
                                .collect();
                            springs.push(Spring::new(
                                vec![(3 * node + d, 1.0)],
                                side_b,
                                k[d] / n_grid * share,
                                c[d] / n_grid * share,
                            ));
                            kinds.push(SpringKind::Fastening);
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

fn add_ballast(
    m: &Model,
    sleepers: &[SleeperTopology],
    springs: &mut Vec<Spring>,
    kinds: &mut Vec<SpringKind>,
) {
    let (k, c) = (m.ballast.stiffness(), m.ballast.damping());
    for s in sleepers {
        let areas = s.bottom_node_areas();
        let total: f64 = areas.iter().map(|a| a.1).sum();
        for &(node, a) in &areas {
            for d in 0..3 {
                springs.push(Spring::new(
                    vec![(3 * node + d, 1.0)],
                    vec![],
                    k[d] * a / total,
                    c[d] * a / total,
                ));
                kinds.push(SpringKind::Ballast);
            }
        }
    }
}

/// The rail-foot DOFs fixed by a hold pattern (sorted, unique).
pub(crate) fn held_dofs(
    p: &HoldPattern,
    layout: &Layout,
    rail: &RailTopology,
) -> Result<Vec<usize>, StructureError> {
    let tol = 1e-7;
    let half = 0.5 * layout.strip_width + tol;
    let foot = &rail.section.foot_underside;
    let foot_s = &rail.section.foot_underside_s_m;
    let planes = &rail.planes_x_m;
    let mut dofs = Vec::new();
    for (d, hold) in [&p.x, &p.y, &p.z].into_iter().enumerate() {
        if hold.rigid != RigidRegion::None && hold.on_node_lines() {
            for &xs in &layout.sleepers {
                for &index in &hold.indices {
                    let line = node_line(layout, rail, hold.rigid, xs, index)?;
                    dofs.extend(line.iter().map(|&(_, node)| 3 * node + d));
                }
            }
            continue;
        }
        match hold.rigid {
            RigidRegion::None => {}
            RigidRegion::GridPoints => {
                for &xs in &layout.sleepers {
                    for (_, node) in grid_point_nodes(layout, rail, xs)? {
                        dofs.push(3 * node + d);
                    }
                }
            }
            RigidRegion::Continuous => {
                for i in 0..planes.len() {
                    dofs.extend(foot.iter().map(|&j| 3 * rail.node(i, j) + d));
                }
            }
            RigidRegion::Columns => {
                for &xs in &layout.sleepers {
                    for &c in &hold.indices {
                        let xc = layout.column_centre(xs, c);
                        let before = dofs.len();
                        for (i, &x) in planes
                            .iter()
                            .enumerate()
                            .filter(|(_, &x)| (x - xc).abs() <= half)
                        {
                            let _ = x;
                            dofs.extend(foot.iter().map(|&j| 3 * rail.node(i, j) + d));
                        }
                        if dofs.len() == before {
                            return Err(StructureError::HoldMissesNodes {
                                what: "column",
                                index: c,
                                axis: "x",
                                position_m: xc,
                                lines: "plane",
                            });
                        }
                    }
                }
            }
            RigidRegion::Rows => {
                for &xs in &layout.sleepers {
                    let (xa, xb) = (
                        xs - 0.5 * layout.footprint_length - tol,
                        xs + 0.5 * layout.footprint_length + tol,
                    );
                    for &r in &hold.indices {
                        let yr = layout.row_centre(r);
                        let before = dofs.len();
                        for (i, _) in planes
                            .iter()
                            .enumerate()
                            .filter(|(_, &x)| x >= xa && x <= xb)
                        {
                            for (k, &j) in foot.iter().enumerate() {
                                if (foot_s[k] - yr).abs() <= half {
                                    dofs.push(3 * rail.node(i, j) + d);
                                }
                            }
                        }
                        if dofs.len() == before {
                            return Err(StructureError::HoldMissesNodes {
                                what: "row",
                                index: r,
                                axis: "y",
                                position_m: yr,
                                lines: "line",
                            });
                        }
                    }
                }
            }
        }
    }
    dofs.sort_unstable();
    dofs.dedup();
    Ok(dofs)
}

/// The rail-foot node at each railpad grid point (row, column cell centre) of the fastening on
/// the sleeper at `xs`, with its share of the grid (1/(rows·columns)). The mesh has node planes
/// and foot lines there ([`Layout::x_breakpoints`], [`Layout::y_foot_lines`]).
fn grid_point_nodes(
    layout: &Layout,
    rail: &RailTopology,
    xs: f64,
) -> Result<Vec<(f64, usize)>, StructureError> {
    let tol = 1e-7;
    let foot = &rail.section.foot_underside;
    let foot_s = &rail.section.foot_underside_s_m;
    let share = 1.0 / (layout.rows * layout.columns) as f64;
    let mut out = Vec::with_capacity(layout.rows * layout.columns);
    for c in 0..layout.columns {
        let xc = layout.grid_point_x(xs, c);
        let i = nearest(&rail.planes_x_m, xc)
            .filter(|&i| (rail.planes_x_m[i] - xc).abs() <= tol)
            .ok_or(StructureError::HoldMissesNodes {
                what: "grid point of column",
                index: c,
                axis: "x",
                position_m: xc,
                lines: "plane",
            })?;
        for r in 0..layout.rows {
            let yr = layout.row_centre(r);
            let k = nearest(foot_s, yr)
                .filter(|&k| (foot_s[k] - yr).abs() <= tol)
                .ok_or(StructureError::HoldMissesNodes {
                    what: "grid point of row",
                    index: r,
                    axis: "y",
                    position_m: yr,
                    lines: "line",
                })?;
            out.push((share, rail.node(i, foot[k])));
        }
    }
    Ok(out)
}

/// The rail-foot underside nodes of one held node line of the fastening on the sleeper at
/// `xs`, with their tributary-length weights along the line (summing to 1): for
/// [`RigidRegion::Columns`] the nodes on the node plane through the centre of column
/// `index`, across the whole foot; for [`RigidRegion::Rows`] the nodes on the foot node
/// line through the centre of row `index`, at the node planes within the footprint length. The
/// mesh has that plane or line ([`Layout::x_breakpoints`], [`Layout::y_foot_lines`]).
pub(crate) fn node_line(
    layout: &Layout,
    rail: &RailTopology,
    region: RigidRegion,
    xs: f64,
    index: usize,
) -> Result<Vec<(f64, usize)>, StructureError> {
    let tol = 1e-7;
    let foot = &rail.section.foot_underside;
    let foot_s = &rail.section.foot_underside_s_m;
    let normalised = |w: Vec<f64>, node: &dyn Fn(usize) -> usize| {
        let total: f64 = w.iter().sum();
        w.iter()
            .enumerate()
            .filter(|(_, &w)| w > 0.0)
            .map(|(k, &w)| (w / total, node(k)))
            .collect::<Vec<_>>()
    };
    if region == RigidRegion::Columns {
        let xc = layout.column_centre(xs, index);
        let i = nearest(&rail.planes_x_m, xc)
            .filter(|&i| (rail.planes_x_m[i] - xc).abs() <= tol)
            .ok_or(StructureError::HoldMissesNodes {
                what: "column line",
                index,
                axis: "x",
                position_m: xc,
                lines: "plane",
            })?;
        let w = tributary_lengths(foot_s, f64::NEG_INFINITY, f64::INFINITY);
        return Ok(normalised(w, &|k| rail.node(i, foot[k])));
    }
    let yr = layout.row_centre(index);
    let k = nearest(foot_s, yr)
        .filter(|&k| (foot_s[k] - yr).abs() <= tol)
        .ok_or(StructureError::HoldMissesNodes {
            what: "row line",
            index,
            axis: "y",
            position_m: yr,
            lines: "line",
        })?;
    let half = 0.5 * layout.footprint_length;
    let w = tributary_lengths(&rail.planes_x_m, xs - half, xs + half);
    Ok(normalised(w, &|i| rail.node(i, foot[k])))
}

fn nearest(v: &[f64], x: f64) -> Option<usize> {
    (0..v.len()).min_by(|&a, &b| (v[a] - x).abs().total_cmp(&(v[b] - x).abs()))
}

/// Grounded spring-dampers of the elastic holds of `p` (see the module docs): for each held
/// direction, the stiffness and damping per fastening spread over the region's foot nodes.
/// Per fastening the stiffnesses sum to the stated k (per sleeper spacing of rail for the
/// continuous region); for node lines each held line's sum to the stated k per line.
pub(crate) fn add_elastic_holds(
    p: &HoldPattern,
    layout: &Layout,
    sleeper_spacing: f64,
    rail: &RailTopology,
    springs: &mut Vec<Spring>,
    kinds: &mut Vec<SpringKind>,
) -> Result<(), StructureError> {
    let foot = &rail.section.foot_underside;
    let foot_s = &rail.section.foot_underside_s_m;
    let planes = &rail.planes_x_m;
    let all_y = tributary_lengths(foot_s, f64::NEG_INFINITY, f64::INFINITY);
    // (share of the per-fastening k, node) pairs of one fastening's region.
    let mut push = |d: usize, k: f64, c: f64, parts: &[(f64, usize)]| {
        for &(share, node) in parts {
            if share > 0.0 {
                springs.push(Spring::new(
                    vec![(3 * node + d, 1.0)],
                    vec![],
                    k * share,
                    c * share,
                ));
                kinds.push(SpringKind::Hold);
            }
        }
    };
    // Nodes of the patch [xa, xb] × [ya, yb] (ya/yb None: the whole foot) with their area
    // fractions of the patch, scaled by `scale`.
    let patch = |xa: f64, xb: f64, ly: &[f64], scale: f64, what: &str| {
        let lx = tributary_lengths(planes, xa, xb);
        let (sx, sy): (f64, f64) = (lx.iter().sum(), ly.iter().sum());
        if sx <= 0.0 || sy <= 0.0 {
            return Err(StructureError::ElasticHoldEmpty {
                what: what.to_string(),
            });
        }
        let mut v = Vec::new();
        for (i, &wx) in lx.iter().enumerate().filter(|(_, &w)| w > 0.0) {
            for (k, &wy) in ly.iter().enumerate().filter(|(_, &w)| w > 0.0) {
                v.push((scale * wx * wy / (sx * sy), rail.node(i, foot[k])));
            }
        }
        Ok(v)
    };
    for (d, hold) in [&p.x, &p.y, &p.z].into_iter().enumerate() {
        let Some((k, c)) = hold.elastic_stiffness_damping() else {
            continue;
        };
        if hold.on_node_lines() {
            // k and c per held line, spread along the line.
            for &xs in &layout.sleepers {
                for &index in &hold.indices {
                    push(d, k, c, &node_line(layout, rail, hold.region(), xs, index)?);
                }
            }
            continue;
        }
        let half = 0.5 * layout.strip_width;
        match hold.region() {
            RigidRegion::None => {}
            RigidRegion::Continuous => {
                // k per fastening = k / s per metre of rail.
                let scale = layout.length / sleeper_spacing;
                push(
                    d,
                    k,
                    c,
                    &patch(0.0, layout.length, &all_y, scale, "the rail foot")?,
                );
            }
            RigidRegion::Columns => {
                let n = hold.indices.len() as f64;
                for &xs in &layout.sleepers {
                    for &col in &hold.indices {
                        let xc = layout.column_centre(xs, col);
                        let what = format!("column {col} at x = {xc} m");
                        push(
                            d,
                            k,
                            c,
                            &patch(xc - half, xc + half, &all_y, 1.0 / n, &what)?,
                        );
                    }
                }
            }
            RigidRegion::Rows => {
                let n = hold.indices.len() as f64;
                for &xs in &layout.sleepers {
                    let (xa, xb) = (
                        xs - 0.5 * layout.footprint_length,
                        xs + 0.5 * layout.footprint_length,
                    );
                    for &r in &hold.indices {
                        let yr = layout.row_centre(r);
                        let ly = tributary_lengths(foot_s, yr - half, yr + half);
                        let what = format!("row {r} at y = {yr} m (sleeper at x = {xs} m)");
                        push(d, k, c, &patch(xa, xb, &ly, 1.0 / n, &what)?);
                    }
                }
            }
            RigidRegion::GridPoints => {
                for &xs in &layout.sleepers {
                    push(d, k, c, &grid_point_nodes(layout, rail, xs)?);
                }
            }
        }
    }
    Ok(())
}
