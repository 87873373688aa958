//! How the contact force couples the track and the wheel over a contact step of the explicit
//! path (docs/theory.md §8.4): the predictor–corrector with the force held at its mean (the
//! default), a ramped corrector, or the last force held without a corrector (the unstable
//! coupling the tests show). The sub-step loads of each are the response module's
//! `Hold`.

use super::response::Hold;

/// How the contact force couples the structures over a contact step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Coupling {
    /// Held-force predictor, contact solved with the one-step compliance, exact linear
    /// corrector to the mean force `(F_n + F_{n+1})/2` held over the step (the default).
    #[default]
    PredictorCorrector,
    /// As [`Coupling::PredictorCorrector`], but the corrector ramps the force linearly from
    /// `F_n` to `F_{n+1}` (first-order hold; unstable when the contact–mass frequency times
    /// the contact step exceeds 2√3; for tests).
    RampCorrector,
    /// The last contact force `F_n` held over the step where it was computed, at the
    /// previous contact position `x_n` (as the reduced passage holds it), no corrector
    /// (unstable when the contact stiffness times the one-step compliance is of order one;
    /// for tests).
    HeldForce,
}

impl Coupling {
    /// Whether the contact is solved with the one-step compliance and the state corrected.
    pub(super) fn corrected(self) -> bool {
        self != Coupling::HeldForce
    }

    /// How the corrector applies the force change over the step's sub-steps.
    pub(super) fn hold(self) -> Hold {
        match self {
            Coupling::RampCorrector => Hold::Ramp,
            _ => Hold::Mean,
        }
    }

    /// The predictor's force (N) in a contact step's first sub-step, with `f` the force held
    /// over the step and `f_prev` the previous step's ([`Hold::first_load`]; `f` when there
    /// is no corrector).
    pub(super) fn first_load(self, f: [f64; 3], f_prev: [f64; 3]) -> [f64; 3] {
        if self.corrected() {
            self.hold().first_load(f, f_prev)
        } else {
            f
        }
    }

    /// [`Self::first_load`] split into the part at the previous contact position and the
    /// part at this one ([`Hold::boundary_split`]; all at this one without a corrector).
    pub(super) fn boundary_split(self, f: [f64; 3], f_prev: [f64; 3]) -> [[f64; 3]; 2] {
        if self.corrected() {
            self.hold().boundary_split(f, f_prev)
        } else {
            [[0.0; 3], f]
        }
    }
}
