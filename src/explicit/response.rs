//! Unit-load responses of the explicit coupling (docs/theory.md §8.4): the state of a
//! substructure one contact step after a unit contact force ramped from 0 to 1, from rest,
//! per contact-frame direction; the rail's for the two node planes around the contact, kept
//! in two slots and recomputed in place as the contact moves on.

use super::operator::{ExplicitOperator, StepScratch};

/// The response of a substructure to a unit force held over one contact step from rest:
/// displacement and half-step velocity, one pair per contact-frame direction.
pub(super) struct UnitResponse {
    pub(super) u: [Vec<f64>; 3],
    pub(super) v: [Vec<f64>; 3],
}

impl UnitResponse {
    /// Zero fields for `n` DOFs.
    pub(super) fn zeros(n: usize) -> Self {
        let z = || [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        UnitResponse { u: z(), v: z() }
    }

    /// The response over `steps` steps of `dt` (s) from rest to a unit load in each
    /// contact-frame direction (`load(d, f)` fills it), ramped linearly from 0 at the
    /// step's start to 1 at its end: sub-step `k` applies `k/steps` of it, and the next
    /// contact step's first sub-step applies the full new force. The structure thus sees the
    /// contact force interpolated linearly between contact steps (first-order hold),
    /// consistent with the contact solver's path-mean traction.
    pub(super) fn compute(
        op: &ExplicitOperator,
        dt: f64,
        steps: usize,
        load: impl Fn(usize, &mut [f64]),
        scratch: &mut StepScratch,
    ) -> Self {
        let n = op.n();
        let mut r = UnitResponse::zeros(n);
        let (mut f, mut fk) = (vec![0.0; n], vec![0.0; n]);
        r.compute_into(op, dt, steps, load, [&mut f, &mut fk], scratch);
        r
    }

    /// [`Self::compute`] into these fields, with the load buffers `f` and `fk` (length n):
    /// no allocation.
    pub(super) fn compute_into(
        &mut self,
        op: &ExplicitOperator,
        dt: f64,
        steps: usize,
        load: impl Fn(usize, &mut [f64]),
        [f, fk]: [&mut [f64]; 2],
        scratch: &mut StepScratch,
    ) {
        for d in 0..3 {
            f.iter_mut().for_each(|x| *x = 0.0);
            load(d, f);
            let (u, v) = (&mut self.u[d], &mut self.v[d]);
            u.iter_mut().for_each(|x| *x = 0.0);
            v.iter_mut().for_each(|x| *x = 0.0);
            for k in 0..steps {
                let a = k as f64 / steps as f64;
                fk.iter_mut().zip(f.iter()).for_each(|(x, y)| *x = a * y);
                op.step(dt, u, v, fk, scratch);
            }
        }
    }

    /// `u += Σ_d s·f_d u_d`, `v += Σ_d s·f_d v_d`.
    pub(super) fn add_to(&self, scale: f64, f: [f64; 3], u: &mut [f64], v: &mut [f64]) {
        for d in 0..3 {
            let a = scale * f[d];
            if a == 0.0 {
                continue;
            }
            u.iter_mut().zip(&self.u[d]).for_each(|(x, r)| *x += a * r);
            v.iter_mut().zip(&self.v[d]).for_each(|(x, r)| *x += a * r);
        }
    }
}

/// The rail's unit responses of the node planes under the patch (lazily computed as the
/// contact moves; a plane's response is reused while the patch covers it).
pub(super) struct RailResponses {
    dt: f64,
    steps: usize,
    /// Slots `(plane, response)`; `usize::MAX` marks an empty one.
    slots: Vec<(usize, UnitResponse)>,
    /// Load buffers of [`UnitResponse::compute_into`].
    f: Vec<f64>,
    fk: Vec<f64>,
}

impl RailResponses {
    /// `slots` empty slots for `n` DOFs (allocated once per passage; at least the most
    /// planes a patch covers, plus one).
    pub(super) fn new(n: usize, dt: f64, steps: usize, slots: usize) -> Self {
        RailResponses {
            dt,
            steps,
            slots: (0..slots.max(2))
                .map(|_| (usize::MAX, UnitResponse::zeros(n)))
                .collect(),
            f: vec![0.0; n],
            fk: vec![0.0; n],
        }
    }

    /// Makes `plane`'s response ready: computed into an empty slot or the slot of a plane
    /// behind `first` (the patch's first plane; the contact only moves forward) when it is
    /// not held yet. No allocation.
    pub(super) fn ensure(
        &mut self,
        op: &ExplicitOperator,
        plane: usize,
        first: usize,
        load: impl Fn(usize, &mut [f64]),
        scratch: &mut StepScratch,
    ) {
        if self.slots.iter().any(|(p, _)| *p == plane) {
            return;
        }
        // An empty slot, else the one farthest behind the patch.
        let i = self
            .slots
            .iter()
            .position(|(p, _)| *p == usize::MAX)
            .or_else(|| {
                (0..self.slots.len())
                    .filter(|&i| self.slots[i].0 < first)
                    .min_by_key(|&i| self.slots[i].0)
            })
            .expect("RailResponses: more planes under the patch than slots");
        self.slots[i].1.compute_into(
            op,
            self.dt,
            self.steps,
            load,
            [&mut self.f, &mut self.fk],
            scratch,
        );
        self.slots[i].0 = plane;
    }

    /// The response of `plane` (made ready by [`Self::ensure`]).
    pub(super) fn response(&self, plane: usize) -> &UnitResponse {
        &self
            .slots
            .iter()
            .find(|(p, _)| *p == plane)
            .expect("RailResponses::ensure not called for this plane")
            .1
    }
}
