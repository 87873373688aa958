//! The set-up shared by the reduced and the explicit passage (docs/theory.md §6, §7.4, §7.5):
//! the contact configuration and grid of a passage, the steady rolling state at the static
//! load, the constant wheel loads (gravity, driving torque, train resistance) and the
//! least-norm placement of the wheel's rigid modes.

use super::record::WidenedGrid;
use super::{PassageError, RailProfile};
use crate::contact::{
    GridSpec, HertzGridParams, Longitudinal, NormalInput, StepInputs, TransientConfig,
    TransientRolling,
};
use crate::model::Model;
use crate::progress::Progress;
use crate::structure::WheelStructure;

/// Relative tolerance of the tangential contact solver in a passage (−): the traction error
/// is about this × µ p_max; default 1e-5 (the contact module's own default is 1e-6). Against
/// a solve at 1e-6 on the default model (140 km/h, 2 and 5 kHz) the force histories differ by
/// at most 6e-5 of the mean F_L, the band RMS of F_L and of the wear by 6e-4 (relative) and
/// the dominant wavelength by less than 1e-5, for about three quarters of the tangential
/// products per step (docs/performance.md §4).
pub const PASSAGE_TANGENTIAL_TOL: f64 = 1e-5;

/// The largest work of a passage's contact grid lengthened for a rail profile
/// ([`grid_for_profile`]), in the units of [`crate::model::MAX_GRID_WORK`]: the passage takes
/// `grid_nx` steps per contact-patch length of `grid_nx × grid_ny` elements of the model's
/// grid, so over a profile `grid_nx · nx' · grid_ny` with the lengthened `nx'`. Four times the
/// model grid's bound (48 times the default 32 × 24 grid's passage time): room for the trial
/// amplitudes up to 5 mm peak-to-trough on the default grid, and for 160 µm on a 64 × 64 grid.
pub(crate) const MAX_PROFILE_GRID_WORK: usize = 4 * crate::model::MAX_GRID_WORK;

/// Memory per element of a passage's contact grid (bytes), an estimate: about 20 state arrays
/// of `f64` per element plus the FFT influence kernels on the doubled `2nx × 2ny` grid.
pub(crate) const CONTACT_BYTES_PER_ELEMENT: f64 = 600.0;

/// Peak-to-trough of a rail profile (m) above which it is not a corrugation (those are tens
/// to hundreds of µm): a larger one is likely a unit slip (heights in mm or m where µm are
/// read) and is warned about ([`implausible_profile`]).
pub(crate) const PLAUSIBLE_PROFILE_PTP_M: f64 = 2e-3;

/// A warning when a rail profile's peak-to-trough `ptp_m` (m) is beyond
/// [`PLAUSIBLE_PROFILE_PTP_M`] (a likely unit slip), else `None`.
pub(crate) fn implausible_profile(ptp_m: f64) -> Option<String> {
    (ptp_m > PLAUSIBLE_PROFILE_PTP_M).then(|| {
        format!(
            "the rail profile's peak-to-trough is {} µm ({:.4} mm): corrugation is tens to hundreds of µm deep; are the heights in µm (not mm or m)?",
            crate::units::m_to_um(ptp_m),
            1e3 * ptp_m
        )
    })
}

/// The contact grid for a passage over a rail profile of peak-to-trough `ptp_m` (m): the
/// model's grid (`contact.grid_margin` × the Hertz semi-axes) covers the static patch on a
/// smooth rail, but over a corrugation the crests ahead of and behind the patch can touch.
/// The undeformed gap `x²/(2R_x) − (rail height)` can close within the static approach
/// `δ_H` only where `x²/(2R_x) ≤ δ_H + ptp`, so the grid is lengthened along x to
/// `L_x ≥ √(2 R_x (δ_H + ptp))` with the **same element size** (hence the same time step
/// `Δt = Δx/V`, so passages over different trial amplitudes stay comparable). Never shrinks
/// the grid; the lateral extent is unchanged (the profile varies along x only). A grid whose
/// work is beyond `MAX_PROFILE_GRID_WORK` is refused ([`PassageError::ProfileGrid`], with
/// its elements, memory and work) before anything is allocated.
pub fn grid_for_profile(
    grid: GridSpec,
    radius_x_m: f64,
    approach_m: f64,
    ptp_m: f64,
) -> Result<GridSpec, PassageError> {
    let need = (2.0 * radius_x_m * (approach_m + ptp_m.max(0.0))).sqrt();
    if !(need.is_finite() && need > grid.half_length_x_m) {
        return Ok(grid);
    }
    let dx = grid.dx();
    // in f64 first: a profile in m read as µm gives an element count beyond usize
    let nx_f = (2.0 * need / dx).ceil().max(grid.nx as f64);
    let work = grid.nx as f64 * nx_f * grid.ny as f64;
    if work.is_nan() || work > MAX_PROFILE_GRID_WORK as f64 {
        let elements = nx_f * grid.ny as f64;
        return Err(PassageError::ProfileGrid {
            ptp_um: crate::units::m_to_um(ptp_m),
            nx: nx_f,
            ny: grid.ny,
            memory_gb: elements * CONTACT_BYTES_PER_ELEMENT / 1e9,
            work_ratio: work / (32.0 * 32.0 * 24.0),
            limit_ratio: MAX_PROFILE_GRID_WORK as f64 / (32.0 * 32.0 * 24.0),
        });
    }
    let nx = nx_f as usize;
    Ok(GridSpec {
        nx,
        half_length_x_m: 0.5 * nx as f64 * dx,
        ..grid
    })
}

/// Checks, before any work, that a passage of `model` over a rail profile of peak-to-trough
/// `ptp_m` (m) has a contact grid within `MAX_PROFILE_GRID_WORK` ([`grid_for_profile`] at
/// the static Hertz approach under the wheel load; the grid's element size does not depend on
/// the speed); returns the warning of `implausible_profile`, if any.
pub fn check_profile_grid(model: &Model, ptp_m: f64) -> Result<Option<String>, PassageError> {
    let cfg = contact_config_for(model, model.run.speed())?;
    let hertz = static_hertz(model, model.vehicle.wheel_load)?;
    grid_for_profile(cfg.grid, cfg.radius_x_m, hertz.approach_m, ptp_m)?;
    Ok(implausible_profile(ptp_m))
}

/// The factor on a contact grid's half-length per widening (−), see [`widen_grid`].
pub(crate) const GRID_WIDENING: f64 = 1.25;

/// The most widenings of a passage's contact grid per direction (−): up to
/// `1.25⁴ ≈ 2.4` times the half-length of the model's grid (and as many reruns).
pub(crate) const MAX_GRID_WIDENINGS: u32 = 4;

/// How many times a passage's contact grid is widened along x and along y beyond the grid of
/// [`passage_contact`] ([`widen_grid`]); the default, none, is the model's grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridWidening {
    /// Widenings along x (rolling direction).
    pub x: u32,
    /// Widenings along y (lateral).
    pub y: u32,
}

impl GridWidening {
    /// Whether the grid is widened at all.
    pub fn any(&self) -> bool {
        self.x > 0 || self.y > 0
    }
}

/// `grid` widened `w.x` times along x and `w.y` times along y: each widening lengthens the
/// half-length by `GRID_WIDENING` at the **same element size** (so the same time step
/// `Δx/V` and resolution), with an even number of elements added, half on either side, so
/// that the elements of `grid` keep their places and the widened grid only adds room around
/// them. A direction not widened is left exactly as it is.
pub fn widen_grid(grid: GridSpec, w: GridWidening) -> GridSpec {
    // (elements, half-length) after k widenings of n elements of size d
    let widen = |n: usize, half: f64, d: f64, k: u32| -> (usize, f64) {
        if k == 0 {
            return (n, half);
        }
        let extra = (0.5 * n as f64 * (GRID_WIDENING.powi(k as i32) - 1.0)).ceil() as usize;
        let n = n + 2 * extra.max(1);
        (n, 0.5 * n as f64 * d)
    };
    let (nx, half_length_x_m) = widen(grid.nx, grid.half_length_x_m, grid.dx(), w.x);
    let (ny, half_length_y_m) = widen(grid.ny, grid.half_length_y_m, grid.dy(), w.y);
    GridSpec {
        nx,
        ny,
        half_length_x_m,
        half_length_y_m,
    }
}

/// Where the contact patch of a failed passage reached its grid, if that is why it failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GridEdgeReached {
    /// The edge: `"x"` or `"y"`.
    pub edge: &'static str,
    /// The normal force then (N).
    pub normal_n: f64,
    /// Time of the step (s).
    pub t_s: f64,
    /// Contact position of the step (m).
    pub x_m: f64,
}

/// The edge at which the contact patch of a failed passage reached its grid, with the step's
/// normal force, time and place, if that is why it failed.
pub(crate) fn patch_at_grid_edge(e: &PassageError) -> Option<GridEdgeReached> {
    match e {
        PassageError::Contact {
            t_s,
            x_m,
            source: crate::contact::ContactError::PatchAtGridEdge { edge, normal_n },
        } => Some(GridEdgeReached {
            edge,
            normal_n: *normal_n,
            t_s: *t_s,
            x_m: *x_m,
        }),
        _ => None,
    }
}

/// The largest normal force, as a multiple of the static wheel load (−), under which a patch
/// that reaches its grid's edge is taken for a deep profile's dynamic load and the passage is
/// rerun on a widened grid. Measured dynamic wheel–rail forces stay below about three times
/// the static load even at dipped joints and wheel flats; a force beyond twice that is a
/// passage whose contact coupling has gone unstable, and a wider grid would only let it run
/// longer. Such a passage is reported as diverged ([`PassageError::Diverged`]).
pub(crate) const MAX_WIDENING_LOAD_FACTOR: f64 = 6.0;

impl WidenedGrid {
    /// The widened grid `grid` after the widenings `w`.
    pub fn new(grid: &GridSpec, w: GridWidening) -> Self {
        WidenedGrid {
            widenings: [w.x, w.y],
            elements: [grid.nx, grid.ny],
            half_lengths_m: [grid.half_length_x_m, grid.half_length_y_m],
        }
    }
}

impl std::fmt::Display for WidenedGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let widened: Vec<String> = ["x", "y"]
            .iter()
            .zip(self.widenings)
            .filter(|(_, k)| *k > 0)
            .map(|(d, k)| format!("by {:.2} along {d}", GRID_WIDENING.powi(k as i32)))
            .collect();
        write!(
            f,
            "a contact grid of {} × {} elements, ±{:.2} × ±{:.2} mm (widened {} at the same element size)",
            self.elements[0],
            self.elements[1],
            1e3 * self.half_lengths_m[0],
            1e3 * self.half_lengths_m[1],
            widened.join(" and ")
        )
    }
}

/// Runs a passage (`passage(widening)`) on the grid of [`passage_contact`] and, each time its
/// contact patch reaches the grid's boundary (`patch_at_grid_edge` of the error `dynamics`
/// finds in it), once more from the start on a grid widened along that edge
/// ([`widen_grid`]), at most `MAX_GRID_WIDENINGS` times per direction; a passage that never
/// reaches the boundary runs once, on the model's grid, exactly as without this. `on_rerun(edge,
/// widening)` is told before each rerun. Returns the result and its widening; a passage that
/// still reaches the boundary after the last widening returns
/// [`PassageError::GridOutgrown`] (through `outgrown`). A patch that reaches the boundary
/// under a normal force above `MAX_WIDENING_LOAD_FACTOR` times `static_load_n` (N) is not
/// rerun: the passage diverged, and [`PassageError::Diverged`] says so (through `outgrown`).
pub fn run_widening_grid<T, E>(
    static_load_n: f64,
    mut passage: impl FnMut(GridWidening) -> Result<T, E>,
    dynamics: impl Fn(&E) -> Option<&PassageError>,
    outgrown: impl FnOnce(PassageError) -> E,
    mut on_rerun: impl FnMut(&'static str, GridWidening),
) -> Result<(T, GridWidening), E> {
    let mut w = GridWidening::default();
    loop {
        let e = match passage(w) {
            Ok(r) => return Ok((r, w)),
            Err(e) => e,
        };
        let Some(GridEdgeReached {
            edge,
            normal_n,
            t_s,
            x_m,
        }) = dynamics(&e).and_then(patch_at_grid_edge)
        else {
            return Err(e);
        };
        if normal_n > MAX_WIDENING_LOAD_FACTOR * static_load_n {
            return Err(outgrown(PassageError::Diverged {
                t_s,
                x_m,
                what: format!(
                    "the normal contact force grew to {normal_n:.0} N, {:.1} times the static wheel load (more than {MAX_WIDENING_LOAD_FACTOR}), until the contact patch left its grid ({edge})",
                    normal_n / static_load_n
                ),
            }));
        }
        let k = if edge == "x" { &mut w.x } else { &mut w.y };
        if *k >= MAX_GRID_WIDENINGS {
            let reason = dynamics(&e).map_or_else(String::new, ToString::to_string);
            return Err(outgrown(PassageError::GridOutgrown {
                widenings: MAX_GRID_WIDENINGS,
                edge,
                reason,
            }));
        }
        *k += 1;
        on_rerun(edge, w);
    }
}

#[cfg(test)]
mod tests {
    use super::{
        check_profile_on_travel, grid_for_profile, implausible_profile, run_widening_grid,
        widen_grid, GridSpec, GridWidening, PassageError, RailProfile, GRID_WIDENING,
        MAX_GRID_WIDENINGS,
    };
    /// A widened grid keeps its element size and the places of the model grid's elements; a
    /// direction not widened stays bit for bit; 1.25 per widening in half-length, at least.
    #[test]
    fn widened_grid_keeps_element_size_and_places() {
        let g = GridSpec {
            nx: 45,
            ny: 24,
            half_length_x_m: 10.03e-3,
            half_length_y_m: 7.54e-3,
        };
        assert_eq!(widen_grid(g, GridWidening::default()), g);
        for (wx, wy) in [(0, 1), (1, 0), (2, 3), (4, 4)] {
            let w = widen_grid(g, GridWidening { x: wx, y: wy });
            for (n0, n1, h0, h1, d0, d1, k) in [
                (
                    g.nx,
                    w.nx,
                    g.half_length_x_m,
                    w.half_length_x_m,
                    g.dx(),
                    w.dx(),
                    wx,
                ),
                (
                    g.ny,
                    w.ny,
                    g.half_length_y_m,
                    w.half_length_y_m,
                    g.dy(),
                    w.dy(),
                    wy,
                ),
            ] {
                if k == 0 {
                    assert_eq!((n1, h1), (n0, h0));
                    continue;
                }
                assert_eq!((n1 - n0) % 2, 0, "{n0} → {n1}");
                assert!((d1 - d0).abs() < 1e-12 * d0, "element size {d0} → {d1}");
                assert!(h1 >= GRID_WIDENING.powi(k as i32) * h0 * (1.0 - 1e-12));
                assert!(h1 < GRID_WIDENING.powi(k as i32) * h0 + 2.0 * d0);
            }
            // the model grid's first element centre is an element centre of the widened grid
            let e = (w.nx - g.nx) / 2;
            assert!((w.x(e) - g.x(0)).abs() < 1e-12);
            let e = (w.ny - g.ny) / 2;
            assert!((w.y(e) - g.y(0)).abs() < 1e-12);
        }
    }

    /// The rerun rule: a passage that never reaches the grid's edge runs once on the model's
    /// grid; each edge reached widens that direction once; other errors pass through; the
    /// last widening that still reaches it is an error naming the widenings; a patch that
    /// reaches it under more than six times the static load is a diverged passage, not rerun.
    #[test]
    fn passages_rerun_on_a_widened_grid_only_when_the_patch_reaches_its_edge() {
        const LOAD: f64 = 1e5;
        let edge_at = |edge, normal_n| PassageError::Contact {
            t_s: 0.01,
            x_m: 0.2,
            source: crate::contact::ContactError::PatchAtGridEdge { edge, normal_n },
        };
        let edge = |edge| edge_at(edge, 3.0 * LOAD);
        fn dynamics(e: &PassageError) -> Option<&PassageError> {
            Some(e)
        }
        let mut calls = Vec::new();
        let r = run_widening_grid(
            LOAD,
            |w| {
                calls.push(w);
                Ok::<_, PassageError>(1)
            },
            dynamics,
            |e| e,
            |_, _| panic!("no rerun"),
        );
        assert_eq!(r.unwrap(), (1, GridWidening::default()));
        assert_eq!(calls, [GridWidening::default()]);
        // y, then x, then runs
        let mut reruns = Vec::new();
        let (_, w) = run_widening_grid(
            LOAD,
            |w| match (w.x, w.y) {
                (0, 0) => Err(edge("y")),
                (0, 1) => Err(edge("x")),
                _ => Ok(()),
            },
            dynamics,
            |e| e,
            |e, w| reruns.push((e, w)),
        )
        .unwrap();
        assert_eq!(w, GridWidening { x: 1, y: 1 });
        assert_eq!(
            reruns,
            [
                ("y", GridWidening { x: 0, y: 1 }),
                ("x", GridWidening { x: 1, y: 1 })
            ]
        );
        // another error is not retried
        let e = run_widening_grid(
            LOAD,
            |_| Err::<(), _>(PassageError::MissingNodes { what: "x" }),
            dynamics,
            |e| e,
            |_, _| panic!("no rerun"),
        );
        assert!(matches!(e, Err(PassageError::MissingNodes { .. })));
        // the edge reached every time: MAX_GRID_WIDENINGS reruns, then the error
        let mut n = 0;
        let e = run_widening_grid(
            LOAD,
            |_| Err::<(), _>(edge("y")),
            dynamics,
            |e| e,
            |_, _| n += 1,
        )
        .unwrap_err();
        assert_eq!(n, MAX_GRID_WIDENINGS);
        let msg = e.to_string();
        assert!(matches!(e, PassageError::GridOutgrown { .. }), "{msg}");
        assert!(
            msg.contains("contact.grid_margin") && msg.contains("(y)"),
            "{msg}"
        );
        // a patch at the edge under 6.5 times the static load: diverged at once, no rerun;
        // under 5.9 times: rerun
        let e = run_widening_grid(
            LOAD,
            |_| Err::<(), _>(edge_at("x", 6.5 * LOAD)),
            dynamics,
            |e| e,
            |_, _| panic!("no rerun"),
        )
        .unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(e, PassageError::Diverged { t_s, x_m, .. } if t_s == 0.01 && x_m == 0.2),
            "{msg}"
        );
        assert!(msg.contains("6.5 times the static wheel load"), "{msg}");
        let mut n = 0;
        let _ = run_widening_grid(
            LOAD,
            |w| match w.x {
                0 => Err(edge_at("x", 5.9 * LOAD)),
                _ => Ok(()),
            },
            dynamics,
            |e| e,
            |_, _| n += 1,
        )
        .unwrap();
        assert_eq!(n, 1);
    }

    /// The reference contact's wheel radius (m), static approach (m) and an `nx × ny` grid
    /// of margin 1.4 around its patch.
    fn reference_grid(nx: usize, ny: usize) -> (f64, f64, GridSpec) {
        let g = GridSpec {
            nx,
            ny,
            half_length_x_m: 1.4 * 7.162e-3,
            half_length_y_m: 1.4 * 5.387e-3,
        };
        (0.46, 104.1e-6, g)
    }

    /// The reference contact (R 0.46 m on the R300 crown, 100 kN: a = 7.162 mm, δ_H = 104.1
    /// µm) on the default grid (44 elements, margin 1.4): closed-form half-length
    /// √(2 R (δ_H + ptp)), element size kept.
    #[test]
    fn grid_grows_with_the_corrugation_depth_at_fixed_element_size() {
        let (r, delta, g) = reference_grid(44, 32);
        // smooth rail: √(2Rδ) = 9.79 mm < 10.03 mm → unchanged
        assert_eq!(grid_for_profile(g, r, delta, 0.0).unwrap(), g);
        for (ptp, nx) in [(10e-6, 45), (160e-6, 69)] {
            let w = grid_for_profile(g, r, delta, ptp).unwrap();
            let need = (2.0 * r * (delta + ptp)).sqrt();
            assert_eq!(w.nx, nx, "ptp {ptp}");
            assert!(w.half_length_x_m >= need && w.half_length_x_m < need + w.dx());
            assert!((w.dx() - g.dx()).abs() < 1e-15);
            assert_eq!((w.ny, w.half_length_y_m), (g.ny, g.half_length_y_m));
        }
        // never shrinks, bad input leaves the grid alone
        assert_eq!(grid_for_profile(g, r, f64::NAN, 1e-4).unwrap(), g);
    }

    /// A profile whose lengthened grid is beyond the work bound is refused before anything
    /// is allocated, with its size and memory (a height of 1e9 µm, 1 km, read as µm); 5 mm
    /// (the largest trial amplitude) passes on this grid.
    #[test]
    fn a_profile_beyond_the_grid_work_bound_is_refused() {
        let (r, delta, g) = reference_grid(32, 24);
        assert!(grid_for_profile(g, r, delta, 5e-3).is_ok());
        for ptp in [1e3, 1e9, f64::MAX] {
            match grid_for_profile(g, r, delta, ptp) {
                Err(PassageError::ProfileGrid { nx, memory_gb, .. }) => {
                    assert!(nx > 5e4 && memory_gb > 1.0, "{ptp}: {nx} {memory_gb}")
                }
                other => panic!("{ptp}: {other:?}"),
            }
        }
        assert!(implausible_profile(160e-6).is_none());
        assert!(implausible_profile(3e-3).is_some());
    }

    /// A profile off the rail the contact passes over is refused with both ranges, one that
    /// partly overlaps it is warned about, and only the heights on it lengthen the grid.
    #[test]
    fn a_profile_is_checked_against_the_rail_the_contact_passes_over() {
        let travel = [1.0, 3.0];
        let p = |x0: f64, x1: f64, h: [f64; 3]| {
            RailProfile::new(vec![x0, 0.5 * (x0 + x1), x1], h.to_vec()).unwrap()
        };
        let off = p(3.01, 4.0, [0.0, 1e-4, 0.0]);
        let e = check_profile_on_travel(&off, travel).unwrap_err();
        assert!(matches!(e, PassageError::ProfileOffTravel { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains("3.0100 … 4.0000 m") && text.contains("1.0000 … 3.0000 m"),
            "{text}"
        );
        assert!(check_profile_on_travel(&p(0.0, 0.99, [0.0; 3]), travel).is_err());
        let inside = p(1.5, 2.5, [0.0, 1e-4, -1e-4]);
        assert_eq!(check_profile_on_travel(&inside, travel).unwrap(), None);
        assert_eq!(
            inside.peak_to_trough_within_m(travel),
            inside.peak_to_trough_m()
        );
        // the 100 µm crest at x = 3.5 lies beyond the travel: met heights are flat
        let partly = p(2.0, 5.0, [0.0, 1e-4, 0.0]);
        let w = check_profile_on_travel(&partly, travel)
            .unwrap()
            .expect("a warning");
        assert!(
            w.contains("2.0000 … 5.0000 m") && w.contains("never met"),
            "{w}"
        );
        // heights interpolated at the travel's end: 0 at 2 m, 2/3 of the crest at 3 m
        let met = partly.peak_to_trough_within_m(travel);
        assert!((met - 1e-4 * 2.0 / 3.0).abs() < 1e-15, "{met}");
        let flat = RailProfile::new(vec![2.0, 3.2, 3.5, 5.0], vec![0.0, 0.0, 1e-4, 0.0]).unwrap();
        assert_eq!(flat.peak_to_trough_within_m(travel), 0.0);
    }
}

/// The constant loads on the wheel substructure as free-DOF vectors (N): gravity on every
/// mass, the driving torque `T = μ_t W R` as a pure couple on the journal nodes, and the
/// train's resistance `−μ_t W` on the journal nodes (docs/theory.md §7.4). Shared by the
/// reduced and the explicit passage so that both apply the same loads.
#[derive(Clone, Debug)]
pub struct WheelLoads {
    /// Gravity `M (−g e_z)` (N).
    pub gravity: Vec<f64>,
    /// The driving torque's journal forces (N).
    pub torque: Vec<f64>,
    /// The train's resistance on the journals (N).
    pub drawbar: Vec<f64>,
    /// Distance of the tread contact node from the axle (m).
    pub contact_radius_m: f64,
}

impl WheelLoads {
    /// The loads of `model` on `wheel` with its assembled matrices.
    pub fn new(
        model: &Model,
        wheel: &WheelStructure,
        wheel_mats: &crate::fe::assembly::FeMatrices,
    ) -> Result<Self, PassageError> {
        let nf = wheel.dofmap.n_free();
        // Gravity: M · (−g e_z) over the free DOFs (mass matrix row sums in z).
        let g = model.vehicle.gravity;
        let mut gravity = vec![0.0; nf];
        {
            let m = wheel_mats.m.as_ref();
            let mut ez = vec![0.0; nf];
            for node in 0..wheel.dofmap.n_nodes() {
                if let Some(r) = wheel.dofmap.free_index(3 * node + 2) {
                    ez[r] = 1.0;
                }
            }
            let cols = m.symbolic().col_ptr();
            let rows = m.symbolic().row_idx();
            let vals = m.val();
            for j in 0..m.ncols() {
                for p in cols[j]..cols[j + 1] {
                    gravity[rows[p]] -= g * vals[p] * ez[j];
                }
            }
        }
        let f_l0 = model.contact.traction_coefficient * model.vehicle.wheel_load;
        let bearing = wheel.topology.bearing_nodes();
        // Contact radius: the tread contact node's distance from the axle.
        let cn = wheel.topology.contact_node();
        let radius = -wheel.mesh.nodes[cn][2];
        // Torque T = F_L0 · R about +y: forces c (ŷ × r_i) on the journal nodes minus their
        // resultant, spread with the balanced weights (which has no moment about the axle), so
        // the load is a pure couple whatever the grading of the node angles.
        let wj = crate::structure::wheel::balanced_journal_weights(&wheel.mesh, &bearing);
        let nw = wheel.dofmap.n_dofs();
        let mut torque_full = vec![0.0; nw];
        let r2: f64 = bearing
            .iter()
            .map(|&b| {
                let p = wheel.mesh.nodes[b];
                p[0] * p[0] + p[2] * p[2]
            })
            .sum();
        if r2 <= 0.0 {
            return Err(PassageError::JournalsOnAxis);
        }
        let t_y = f_l0 * radius;
        let (mut sx, mut sz) = (0.0, 0.0);
        for &b in &bearing {
            let p = wheel.mesh.nodes[b];
            torque_full[3 * b] += t_y / r2 * p[2];
            torque_full[3 * b + 2] += -t_y / r2 * p[0];
            sx += t_y / r2 * p[2];
            sz += -t_y / r2 * p[0];
        }
        let mut drawbar_full = vec![0.0; nw];
        for (&b, &w) in bearing.iter().zip(&wj) {
            torque_full[3 * b] -= w * sx;
            torque_full[3 * b + 2] -= w * sz;
            drawbar_full[3 * b] -= f_l0 * w;
        }
        let restrict = |full: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; nf];
            for (d, &f) in full.iter().enumerate() {
                if let Some(r) = wheel.dofmap.free_index(d) {
                    out[r] = f;
                }
            }
            out
        };
        Ok(WheelLoads {
            gravity,
            torque: restrict(&torque_full),
            drawbar: restrict(&drawbar_full),
            contact_radius_m: radius,
        })
    }

    /// Gravity + torque + resistance (N).
    pub fn total(&self) -> Vec<f64> {
        (0..self.gravity.len())
            .map(|i| self.gravity[i] + self.torque[i] + self.drawbar[i])
            .collect()
    }
}

/// The elastic constants `(E (Pa), ν (−))` of the contact's half-spaces for `model`: the
/// rail's and the wheel's steel combined as quasi-identical bodies
/// ([`crate::contact::quasi_identical_pair`]); the rail's own when the two are the same.
pub fn contact_steel(model: &Model) -> (f64, f64) {
    crate::contact::quasi_identical_pair(
        (model.rail.youngs_modulus, model.rail.poisson_ratio),
        (model.wheel.youngs_modulus, model.wheel.poisson_ratio),
    )
}

/// The contact configuration of a passage of `model` at `speed_m_per_s` (m/s) under the wheel
/// load: the model's grid around the static Hertz patch, and the tangential tolerance
/// [`PASSAGE_TANGENTIAL_TOL`]. The reduced and the explicit passage use it alike.
pub fn contact_config_for(
    model: &Model,
    speed_m_per_s: f64,
) -> Result<TransientConfig, PassageError> {
    let m = model;
    let (youngs_pa, poisson) = contact_steel(m);
    let mut cfg = TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: m.wheel.radius,
        radius_y_m: m.contact.rail_crown_radius,
        youngs_pa,
        poisson,
        friction: m.contact.friction,
        speed_m_per_s,
        load_n: m.vehicle.wheel_load,
        nx: m.contact.grid_nx,
        ny: m.contact.grid_ny,
        margin: m.contact.grid_margin,
    })
    .map_err(PassageError::ContactGrid)?;
    cfg.tangential_tol = PASSAGE_TANGENTIAL_TOL;
    Ok(cfg)
}

/// A rail profile on a passage: what [`passage_grid`] lengthens the contact grid for.
#[derive(Clone, Copy, Debug)]
pub struct ProfileOnRail<'a> {
    /// The profile.
    pub profile: &'a RailProfile,
    /// The static Hertz approach (m).
    pub approach_m: f64,
    /// The rail the contact grid passes over in the passage, `[from, to]` (m):
    /// [`rail_under_contact_m`].
    pub travel_m: [f64; 2],
}

impl<'a> ProfileOnRail<'a> {
    /// `profile` (if any) with the static Hertz approach `approach_m` (m) on the rail
    /// `travel_m()` gives (called only for a profile).
    pub fn of<E>(
        profile: Option<&'a RailProfile>,
        approach_m: f64,
        travel_m: impl FnOnce() -> Result<[f64; 2], E>,
    ) -> Result<Option<Self>, E> {
        profile
            .map(|p| {
                Ok(ProfileOnRail {
                    profile: p,
                    approach_m,
                    travel_m: travel_m()?,
                })
            })
            .transpose()
    }
}

/// The stretch of rail `[from, to]` (m) the contact grid `grid` (the model's, around the
/// static patch) passes over in a passage whose wheel starts at `x_start_m` and runs until
/// the grid has left the solution zone ending at `zone_end_m` (m): from the start less the
/// grid's half-length `L` to the last contact position (`zone end + L + 2Δx`, and a step of
/// rounding) plus `L`. Heights of a rail profile outside it are never sampled.
pub fn rail_under_contact_m(x_start_m: f64, zone_end_m: f64, grid: &GridSpec) -> [f64; 2] {
    let (l, dx) = (grid.half_length_x_m, grid.dx());
    [x_start_m - l, zone_end_m + 2.0 * l + 3.0 * dx]
}

/// Checks a rail profile against the rail the contact passes over (`travel_m`,
/// [`rail_under_contact_m`]): [`PassageError::ProfileOffTravel`] when its samples lie
/// entirely off it; the warning to give when they only partly overlap it (the heights off
/// it are never met), `None` when they lie on it.
pub fn check_profile_on_travel(
    profile: &RailProfile,
    travel_m: [f64; 2],
) -> Result<Option<String>, PassageError> {
    let x = &profile.x_m;
    let span = [x[0], x[x.len() - 1]];
    if span[1] < travel_m[0] || span[0] > travel_m[1] {
        return Err(PassageError::ProfileOffTravel {
            profile_m: span,
            travel_m,
        });
    }
    Ok((span[0] < travel_m[0] || span[1] > travel_m[1]).then(|| {
        format!(
            "the rail profile spans x = {:.4} … {:.4} m but the wheel's contact passes over x = {:.4} … {:.4} m only (its travel ± the contact grid's half-length): the heights outside are never met",
            span[0], span[1], travel_m[0], travel_m[1]
        )
    }))
}

/// The transient contact of a passage of `model` at `speed_m_per_s` (m/s, finite and > 0):
/// [`contact_config_for`], with the grid lengthened for a rail profile by
/// [`grid_for_profile`] (for the part of it the contact meets: [`passage_grid`]), then widened
/// by `widening` ([`widen_grid`]; the default leaves it), on the influence operators of
/// `contact.influence` ([`super::fe_patch::influence_for`]: the half-spaces, or the
/// fe-patch of that grid, built on first use). The reduced and the explicit passage use it
/// alike.
pub fn passage_contact(
    model: &Model,
    speed_m_per_s: f64,
    profile: Option<ProfileOnRail<'_>>,
    widening: GridWidening,
) -> Result<TransientRolling, PassageError> {
    check_speed(speed_m_per_s)?;
    let mut cfg = contact_config_for(model, speed_m_per_s)?;
    cfg.grid = passage_grid(&cfg, profile, widening)?;
    let hertz_b_m = static_hertz(model, model.vehicle.wheel_load)?.b_m;
    let beside = super::fe_patch::Beside::GlobalModel;
    match super::fe_patch::influence_for(model, (&cfg, hertz_b_m), beside, None)? {
        None => TransientRolling::new(cfg),
        Some(op) => TransientRolling::with_influence(cfg, op),
    }
    .map_err(PassageError::ContactGrid)
}

/// The fe-patch of the model's own contact configuration at its speed (its twins loaded as
/// the static Hertz patch of its wheel load), built or read before any passage
/// ([`super::fe_patch::prepare`]; nothing for the half-space).
pub fn prepare_fe_patch(
    model: &Model,
    progress: Option<&dyn Progress>,
) -> Result<(), PassageError> {
    let cfg = contact_config_for(model, model.run.speed())?;
    let hertz_b_m = static_hertz(model, model.vehicle.wheel_load)?.b_m;
    super::fe_patch::prepare(model, &cfg, hertz_b_m, progress)
}

/// The grid of [`passage_contact`] from the model's contact configuration `cfg`
/// ([`contact_config_for`]): lengthened for the peak-to-trough height of the part of the
/// profile on the rail the contact passes over
/// (`RailProfile::peak_to_trough_within_m`; heights it never meets change nothing), then
/// widened.
pub fn passage_grid(
    cfg: &TransientConfig,
    profile: Option<ProfileOnRail<'_>>,
    widening: GridWidening,
) -> Result<GridSpec, PassageError> {
    let grid = match profile {
        Some(p) => grid_for_profile(
            cfg.grid,
            cfg.radius_x_m,
            p.approach_m,
            p.profile.peak_to_trough_within_m(p.travel_m),
        )?,
        None => cfg.grid,
    };
    Ok(widen_grid(grid, widening))
}

/// The static Hertz patch of the model's wheel on its rail crown under a vertical load
/// `load_n` (N): the patch every passage, the explicit path and the compliance check build
/// their contact line from.
pub fn static_hertz(
    model: &Model,
    load_n: f64,
) -> Result<crate::contact::HertzContact, PassageError> {
    let (youngs_pa, poisson) = contact_steel(model);
    crate::contact::HertzContact::solve(&crate::contact::HertzInput {
        radius_x_m: model.wheel.radius,
        radius_y_m: model.contact.rail_crown_radius,
        youngs_pa,
        poisson,
        load_n,
    })
    .map_err(PassageError::StaticHertz)
}

/// Position along the rail (m) from which the driving torque and the train's resistance act,
/// both engines: −∞ for the static start (always), `zone_start_m − run.rest_start_distance`
/// for the start from rest, refused when that lies before the wheel's start `x_start_m` (m)
/// ([`crate::model::Model::run_in_m`]).
pub fn torque_onset_m(
    model: &Model,
    x_start_m: f64,
    zone_start_m: f64,
) -> Result<f64, PassageError> {
    match model.run.start {
        crate::model::StartKind::Static => Ok(f64::NEG_INFINITY),
        crate::model::StartKind::Rest => {
            let x = zone_start_m - model.run.rest_start_distance;
            if x < x_start_m - 1e-9 {
                return Err(PassageError::OutOfRange {
                    name: "run.rest_start_distance (m)",
                    value: model.run.rest_start_distance,
                    expected: "at most the run-in, the distance from the wheel's start to the solution zone (raise run.solution_zone_offset, and track.bays if the track is too short)",
                });
            }
            Ok(x)
        }
    }
}

/// The longitudinal contact force of a passage's start (N, on the wheel): `μ_t W` for the
/// static start (steady rolling under traction), 0 for the start from rest (free rolling;
/// the torque comes on later, [`torque_onset_m`]).
pub fn start_longitudinal_force_n(model: &Model) -> f64 {
    match model.run.start {
        crate::model::StartKind::Static => {
            model.contact.traction_coefficient * model.vehicle.wheel_load
        }
        crate::model::StartKind::Rest => 0.0,
    }
}

/// A passage's speed must be finite and > 0 (m/s).
pub(crate) fn check_speed(speed_m_per_s: f64) -> Result<(), PassageError> {
    if speed_m_per_s > 0.0 && speed_m_per_s.is_finite() {
        Ok(())
    } else {
        Err(PassageError::OutOfRange {
            name: "speed (m/s)",
            value: speed_m_per_s,
            expected: "finite and > 0",
        })
    }
}

/// Brings the contact to steady rolling at the static load (normal force `f_n0`, longitudinal
/// force `f_l0`, N) by stepping with constant inputs until the creepage settles (relative
/// change ≤ 1e-6, at most 20 grid lengths): the static start of a passage.
pub fn steady_contact(
    contact: &mut TransientRolling,
    f_n0: f64,
    f_l0: f64,
    spin_per_m: f64,
    heights: Option<&[f64]>,
    x0: f64,
) -> Result<crate::contact::StepResult, PassageError> {
    let nx = contact.config().grid.nx;
    let mut res = None;
    let mut prev_xi = f64::NAN;
    for k in 0..(20 * nx) {
        let r = contact
            .step(&StepInputs {
                normal: NormalInput::Force(f_n0),
                longitudinal: Longitudinal::Force(f_l0),
                lateral_creepage: 0.0,
                spin_per_m,
                rail_height_m: heights,
            })
            .map_err(|source| PassageError::Contact {
                t_s: 0.0,
                x_m: x0,
                source,
            })?;
        let done = k > 2 * nx && (r.creepage - prev_xi).abs() <= 1e-6 * r.creepage.abs().max(1e-6);
        prev_xi = r.creepage;
        res = Some(r);
        if done {
            break;
        }
    }
    res.ok_or(PassageError::MissingNodes {
        what: "columns in the contact grid",
    })
}

/// The least-norm combination of the wheel's rigid modes that meets three observations:
/// `o[k]` holds what rigid mode `k` shows at (contact x, contact n, axle x); returns the
/// mode coefficients `c = Oᵀ (O Oᵀ)⁻¹ b` (a tiny Tikhonov term guards against rank loss).
pub fn rigid_least_norm(o: &[[f64; 3]], b: [f64; 3]) -> Vec<f64> {
    let mut g = [[0.0; 3]; 3];
    for oi in o {
        for a in 0..3 {
            for c in 0..3 {
                g[a][c] += oi[a] * oi[c];
            }
        }
    }
    let tr_g = g[0][0] + g[1][1] + g[2][2];
    for (a, row) in g.iter_mut().enumerate() {
        row[a] += 1e-12 * tr_g;
    }
    let m = nalgebra::Matrix3::from_fn(|r, c| g[r][c]);
    let y = m
        .lu()
        .solve(&nalgebra::Vector3::new(b[0], b[1], b[2]))
        .unwrap_or_else(nalgebra::Vector3::zeros);
    o.iter()
        .map(|ok| ok[0] * y[0] + ok[1] * y[1] + ok[2] * y[2])
        .collect()
}
