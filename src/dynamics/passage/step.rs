//! The passage's step loop, its phases: one contact step (the approach and the creepages
//! from the predicted modal motion, the rail heights under the grid, the transient contact
//! advanced), the rail point's record, the step count and the finiteness check
//! (docs/theory.md §7.2–§7.4).

use super::super::integrator::ModalVerlet;
use super::super::record::RailPointRecord;
use super::super::reduced::dot;
use super::super::{DynamicsError, RailProfile};
use super::PassageEngine;
use crate::contact::{Longitudinal, NormalInput, StepInputs, TransientRolling};

impl PassageEngine {
    /// One contact step of the passage at time `t` (s) with the contact at `xc` (m), speed
    /// `v` (m/s) and spin `spin` (1/m): the approach and the creepages from the predicted
    /// motion of rail (contact rows `rr`) and wheel, the consistent compliance followed, the
    /// rail heights under the grid, the transient contact advanced. The creepages are the
    /// relative velocity at the step's end over `v`, or, when `start` holds the rail's and
    /// the wheel's contact displacements at the step's start (m, frame x, t, n; read with
    /// the same rows), the relative displacement increment over `v Δt`
    /// (`run.creepage = "increment"`). Returns the step's result and `[ξ (−), δ (m)]`, the
    /// longitudinal creepage and the approach it was given.
    pub(super) fn contact_step(
        &self,
        contact: &mut TransientRolling,
        road: &mut RoadAhead<'_>,
        (rr, tr, wh): (&[f64], &ModalVerlet, &ModalVerlet),
        start: Option<[[f64; 3]; 2]>,
        [t, xc, v, spin]: [f64; 4],
    ) -> Result<(crate::contact::StepResult, [f64; 2]), DynamicsError> {
        let (u_r, v_r) = contact_motion(rr, tr);
        let (u_w, v_w) = contact_motion(&self.wheel_contact.rows, wh);
        self.follow_consistent_compliance(contact, t, xc)?;
        let delta = u_r[2] - u_w[2];
        // The relative rate of the wheel's contact point against the rail's (x, t; m/s).
        let rate = match start {
            Some([ur0, uw0]) => {
                let dt = tr.dt();
                [0, 1].map(|d| ((u_w[d] - uw0[d]) - (u_r[d] - ur0[d])) / dt)
            }
            None => [0, 1].map(|d| v_w[d] - v_r[d]),
        };
        let xi = rate[0] / v;
        let eta = rate[1] / v;
        let r = contact
            .step(&StepInputs {
                normal: NormalInput::Approach(delta),
                longitudinal: Longitudinal::Creepage(xi),
                lateral_creepage: eta,
                spin_per_m: spin,
                rail_height_m: road.heights_at(xc),
            })
            .map_err(|source| {
                DynamicsError::Passage(crate::passage::PassageError::Contact {
                    t_s: t,
                    x_m: xc,
                    source,
                })
            })?;
        Ok((r, [xi, delta]))
    }

    /// The number of contact steps of length `dx` (m) from the start until the grid of half
    /// length `half_grid` (m) has left the zone, with two steps to spare.
    pub(super) fn step_count(&self, half_grid: f64, dx: f64) -> usize {
        let x_end = self.zone_m[1] + half_grid + 2.0 * dx;
        ((x_end - self.x_start_m) / dx).ceil() as usize
    }

    /// An empty record of the rail point's displacement for `n_steps` steps, when the
    /// passage records one.
    pub(super) fn rail_point_record(&self, n_steps: usize) -> Option<RailPointRecord> {
        self.track_modes_for_point
            .as_ref()
            .map(|(_, pos, _)| RailPointRecord {
                position_m: *pos,
                displacement_m: Vec::with_capacity(n_steps),
            })
    }

    /// Appends the rail point's displacement (x, t, n; m) from the track's modal state, when
    /// the passage records one.
    pub(super) fn record_rail_point(&self, rec: Option<&mut RailPointRecord>, tr: &ModalVerlet) {
        if let (Some(rec), Some((_, _, rows))) = (rec, self.track_modes_for_point.as_ref()) {
            let mt = tr.len();
            rec.displacement_m.push([
                dot(&rows[..mt], &tr.q),
                dot(&rows[mt..2 * mt], &tr.q),
                dot(&rows[2 * mt..], &tr.q),
            ]);
        }
    }
}

/// The rail-top heights under the contact grid (m) as the contact moves over a profile;
/// `None` on a smooth rail. The buffer is allocated once per passage.
pub(super) struct RoadAhead<'a> {
    profile: Option<&'a RailProfile>,
    /// The grid's x positions relative to the contact point (m).
    xs: Vec<f64>,
    /// The heights at `xc + xs` (m).
    heights: Vec<f64>,
}

impl<'a> RoadAhead<'a> {
    pub(super) fn new(contact: &TransientRolling, profile: Option<&'a RailProfile>) -> Self {
        let xs = contact.x_m().to_vec();
        let heights = vec![0.0; xs.len()];
        Self {
            profile,
            xs,
            heights,
        }
    }

    /// The heights under the grid with the contact at `xc` (m), or `None` on a smooth rail.
    pub(super) fn heights_at(&mut self, xc: f64) -> Option<&[f64]> {
        let p = self.profile?;
        for (h, &x) in self.heights.iter_mut().zip(&self.xs) {
            *h = p.height_at(xc + x);
        }
        Some(&self.heights)
    }
}

/// An error when a modal coordinate of track or wheel is no longer finite at time `t` (s),
/// contact at `xc` (m).
pub(super) fn check_finite(
    (tr, wh): (&ModalVerlet, &ModalVerlet),
    t: f64,
    xc: f64,
) -> Result<(), DynamicsError> {
    if tr.q.iter().all(|x| x.is_finite()) && wh.q.iter().all(|x| x.is_finite()) {
        return Ok(());
    }
    Err(DynamicsError::Passage(
        crate::passage::PassageError::Diverged {
            t_s: t,
            x_m: xc,
            what: "modal coordinates".into(),
        },
    ))
}

/// The displacement at the contact (frame components x, t, n; m) of a modal system whose
/// contact rows are `rows` (3 × the mode count, by direction).
pub(super) fn contact_displacement(rows: &[f64], it: &ModalVerlet) -> [f64; 3] {
    let m = it.len();
    [0, 1, 2].map(|d| dot(&rows[d * m..(d + 1) * m], &it.q))
}

/// The displacement and the predicted velocity at the contact (frame components x, t, n; m
/// and m/s) of a modal system whose contact rows are `rows` (3 × the mode count, by
/// direction).
fn contact_motion(rows: &[f64], it: &ModalVerlet) -> ([f64; 3], [f64; 3]) {
    let m = it.len();
    let mut u = [0.0; 3];
    let mut vel = [0.0; 3];
    for d in 0..3 {
        let r = &rows[d * m..(d + 1) * m];
        let mut su = 0.0;
        let mut sv = 0.0;
        for i in 0..m {
            su += r[i] * it.q[i];
            sv += r[i] * it.predicted_velocity(i);
        }
        u[d] = su;
        vel[d] = sv;
    }
    (u, vel)
}
