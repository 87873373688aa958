//! Geometry of the supports along the track, independent of any mesh.
//!
//! Sleeper `i` (0-based) is centred at `x_i = (i + ½)·s` (s the sleeper spacing), so the rail,
//! `bays·s` long, overhangs half a bay beyond the first and last sleeper. A fastening's
//! footprint (`footprint_length` along x × `footprint_width` across y, centred on the sleeper
//! and on the rail centre line) is divided into `columns` along x and `rows` across y: cell
//! (r, c) carries one spring-damper of the `rows × columns` grid (docs/theory.md §3.2). A held
//! (rigid or elastic) *column* c is the strip `|x − x_c| ≤ w/2` across the whole foot; a held
//! *row* r is the strip `|y − y_r| ≤ w/2` over the footprint length (w = `strip_width`). These
//! regions have a physical size, so the held stiffness converges under mesh refinement
//! (docs/theory.md §3.3); held *grid points* (one node per cell centre) and *node lines* (the
//! foot nodes on the node plane through a column centre, or on the foot node line through a
//! row centre within the footprint) do not.

use crate::model::{HoldPattern, Model, RigidRegion};

/// Support layout of one model.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Rail length (m).
    pub length: f64,
    /// Sleeper centres along x (m).
    pub sleepers: Vec<f64>,
    /// Footprint length along x (m).
    pub footprint_length: f64,
    /// Footprint width across y (m).
    pub footprint_width: f64,
    /// Number of spring columns along x.
    pub columns: usize,
    /// Number of spring rows across y.
    pub rows: usize,
    /// Width of a held strip (m).
    pub strip_width: f64,
    /// Wheel start x (m): the solution zone is centred on the track.
    pub wheel_start: f64,
    /// Solution zone `[start, end]` (m).
    pub solution_zone: [f64; 2],
    /// Fine-mesh zone `[start, end]` (m): from the wheel start to past the solution zone.
    pub fine_zone: [f64; 2],
}

impl Layout {
    /// The layout of a model.
    pub fn new(m: &Model) -> Layout {
        let s = m.track.sleeper_spacing;
        let length = m.track_length();
        let sleepers = (0..m.track.bays).map(|i| (i as f64 + 0.5) * s).collect();
        let f = &m.fastening;
        let zone_len = m.run.solution_zone_length;
        let offset = m.run.solution_zone_offset;
        // Centre the solution zone on the track.
        let zone_start = 0.5 * (length - zone_len);
        let wheel_start = (zone_start - offset).max(0.0);
        let margin = m.mesh.element_length;
        Layout {
            length,
            sleepers,
            footprint_length: f.footprint_length,
            footprint_width: f.footprint_width,
            columns: f.columns,
            rows: f.rows,
            strip_width: f.strip_width,
            wheel_start,
            solution_zone: [zone_start, zone_start + zone_len],
            fine_zone: [
                (wheel_start - margin).max(0.0),
                (zone_start + zone_len + margin).min(length),
            ],
        }
    }

    /// Centre x of column `c` of the fastening on the sleeper at `xs` (m).
    pub fn column_centre(&self, xs: f64, c: usize) -> f64 {
        let pitch = self.footprint_length / self.columns as f64;
        xs - 0.5 * self.footprint_length + (c as f64 + 0.5) * pitch
    }

    /// Centre y of row `r` (m), rows counted along +y.
    pub fn row_centre(&self, r: usize) -> f64 {
        let pitch = self.footprint_width / self.rows as f64;
        -0.5 * self.footprint_width + (r as f64 + 0.5) * pitch
    }

    /// x-range `[a, b]` of column cell `c` on the sleeper at `xs` (m).
    pub(crate) fn column_cell(&self, xs: f64, c: usize) -> [f64; 2] {
        let pitch = self.footprint_length / self.columns as f64;
        let a = xs - 0.5 * self.footprint_length + c as f64 * pitch;
        [a, a + pitch]
    }

    /// y-range `[a, b]` of row cell `r` (m).
    pub(crate) fn row_cell(&self, r: usize) -> [f64; 2] {
        let pitch = self.footprint_width / self.rows as f64;
        let a = -0.5 * self.footprint_width + r as f64 * pitch;
        [a, a + pitch]
    }

    /// Node x of grid column `c` (the railpad grid point) on the sleeper at `xs` (m): the
    /// column centre.
    pub(crate) fn grid_point_x(&self, xs: f64, c: usize) -> f64 {
        self.column_centre(xs, c)
    }

    /// x-coordinates that must be node planes of the rail mesh: the rail ends and the strip
    /// edges of every held column of `hold` (rigid or elastic, any direction; its centre when
    /// held on node lines), the footprint ends where rows are held and the column centres
    /// where grid points are held, sorted and deduplicated. Spring cells need no node planes: their tributary weights are clipped to
    /// the cell exactly.
    pub(crate) fn x_breakpoints(&self, hold: &HoldPattern) -> Vec<f64> {
        let mut v = vec![0.0, self.length];
        for h in [&hold.x, &hold.y, &hold.z] {
            if h.region() != RigidRegion::Columns {
                continue;
            }
            for &xs in &self.sleepers {
                for &c in &h.indices {
                    let xc = self.column_centre(xs, c);
                    if h.on_node_lines() {
                        // A held column line is the node plane through the column centre.
                        v.push(xc);
                    } else {
                        v.extend([xc - 0.5 * self.strip_width, xc + 0.5 * self.strip_width]);
                    }
                }
            }
        }
        for h in [&hold.x, &hold.y, &hold.z] {
            match h.region() {
                // Rows are held over the footprint length: its ends are node planes.
                RigidRegion::Rows => {
                    for &xs in &self.sleepers {
                        v.extend([
                            xs - 0.5 * self.footprint_length,
                            xs + 0.5 * self.footprint_length,
                        ]);
                    }
                }
                RigidRegion::GridPoints => {
                    for &xs in &self.sleepers {
                        v.extend((0..self.columns).map(|c| self.grid_point_x(xs, c)));
                    }
                }
                _ => {}
            }
        }
        sort_dedup(v)
    }

    /// y-coordinates (rail-section frame, upright) that must be node lines on the foot
    /// underside: the strip edges of every held row of `hold` (rigid or elastic; its centre
    /// when held on node lines) and the row centres where grid points are held.
    pub(crate) fn y_foot_lines(&self, hold: &HoldPattern) -> Vec<f64> {
        let mut v = Vec::new();
        for h in [&hold.x, &hold.y, &hold.z] {
            match h.region() {
                RigidRegion::Rows => {
                    for &r in &h.indices {
                        let yc = self.row_centre(r);
                        if h.on_node_lines() {
                            // A held row line is the foot node line through the row centre.
                            v.push(yc);
                        } else {
                            v.extend([yc - 0.5 * self.strip_width, yc + 0.5 * self.strip_width]);
                        }
                    }
                }
                RigidRegion::GridPoints => v.extend((0..self.rows).map(|r| self.row_centre(r))),
                _ => {}
            }
        }
        sort_dedup(v)
    }
}

/// Coordinates closer than this are the same point (m).
pub(crate) const GEOMETRY_TOLERANCE: f64 = 1e-9;

fn sort_dedup(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() < GEOMETRY_TOLERANCE);
    v
}

/// Tributary lengths of nodes on a line, clipped to `[a, b]`: node `k` at `coords[k]`
/// (sorted ascending) owns the interval between the midpoints to its neighbours (the line
/// ends at the first and last node). Returns the overlap of each node's interval with
/// `[a, b]` (m). The lengths sum to the part of `[a, b]` covered by the nodes: this is the
/// trapezoidal-rule weight, so a uniform pressure on `[a, b]` is distributed exactly.
pub(crate) fn tributary_lengths(coords: &[f64], a: f64, b: f64) -> Vec<f64> {
    let n = coords.len();
    (0..n)
        .map(|k| {
            let lo = if k == 0 {
                coords[0]
            } else {
                0.5 * (coords[k - 1] + coords[k])
            };
            let hi = if k + 1 == n {
                coords[n - 1]
            } else {
                0.5 * (coords[k] + coords[k + 1])
            };
            (hi.min(b) - lo.max(a)).max(0.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{tributary_lengths, Layout, Model};
    #[test]
    fn sleepers_and_zone_of_the_default_model() {
        let m = Model::default_model();
        let l = Layout::new(&m);
        assert_eq!(l.sleepers.len(), m.track.bays);
        assert!((l.sleepers[0] - 0.3).abs() < 1e-12);
        assert!((l.length - 0.6 * m.track.bays as f64).abs() < 1e-12);
        // The zone is centred and starts `solution_zone_offset` after the wheel.
        let [z0, z1] = l.solution_zone;
        assert!((0.5 * (z0 + z1) - 0.5 * l.length).abs() < 1e-12);
        assert!((z0 - l.wheel_start - m.run.solution_zone_offset).abs() < 1e-12);
    }

    #[test]
    fn cells_tile_the_footprint_and_strips_sit_in_their_cells() {
        let m = Model::default_model();
        let l = Layout::new(&m);
        let xs = l.sleepers[3];
        let total: f64 = (0..l.columns)
            .map(|c| l.column_cell(xs, c))
            .map(|[a, b]| b - a)
            .sum();
        assert!((total - l.footprint_length).abs() < 1e-12);
        assert!(
            (l.column_centre(xs, 1) - xs).abs() < 1e-12,
            "middle column on the sleeper axis"
        );
        for r in 0..l.rows {
            let [a, b] = l.row_cell(r);
            let y = l.row_centre(r);
            assert!(a < y - l.strip_width / 2.0 && y + l.strip_width / 2.0 < b);
        }
        // Default: 4 held rows over 140 mm: strip edges at ±7.5, ±27.5, ±42.5, ±62.5 mm.
        let hold = m.fastening.hold_pattern();
        let ys = l.y_foot_lines(&hold);
        let want = [
            -0.0625, -0.0425, -0.0275, -0.0075, 0.0075, 0.0275, 0.0425, 0.0625,
        ];
        assert_eq!(ys.len(), want.len());
        for (y, w) in ys.iter().zip(want) {
            assert!((y - w).abs() < 1e-12, "{ys:?}");
        }
        // RPM3 holds the middle column: its strip edges (±10 mm about the sleeper axis) and the
        // footprint ends (rows are held over the footprint) are node planes.
        let xb = l.x_breakpoints(&hold);
        for want in [xs - 0.085, xs - 0.01, xs + 0.01, xs + 0.085] {
            assert!(
                xb.iter().any(|x| (x - want).abs() < 1e-12),
                "missing {want}"
            );
        }
    }

    #[test]
    fn tributary_lengths_integrate_uniform_load_exactly() {
        // Irregular nodes; a cell inside the covered range: lengths sum to the cell length,
        // and the first moment is exact for a linear field (trapezoidal rule).
        let x = [0.0, 0.01, 0.025, 0.03, 0.06, 0.08];
        let w = tributary_lengths(&x, 0.01, 0.06);
        assert!((w.iter().sum::<f64>() - 0.05).abs() < 1e-15);
        let w = tributary_lengths(&x, 0.0, 0.08);
        assert!((w.iter().sum::<f64>() - 0.08).abs() < 1e-15);
        let moment: f64 = w.iter().zip(&x).map(|(w, x)| w * x).sum();
        assert!((moment - 0.08 * 0.08 / 2.0).abs() < 2e-4, "{moment}"); // trapezoid: O(h²)
                                                                        // A cell outside the nodes gets nothing.
        assert!(tributary_lengths(&x, 0.1, 0.2).iter().all(|&v| v == 0.0));
    }
}
