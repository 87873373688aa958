//! The time and memory of an explicit passage, estimated from its plan before it runs
//! ([`ExplicitEstimate`]), and the bound beyond which it is refused.
//!
//! The estimate is `contact steps × (track sub-steps × track DOFs + wheel sub-steps × wheel
//! DOFs) × ``SECONDS_PER_DOF_SUBSTEP`: the sub-steps' products `K u` dominate (the contact
//! step's own cost is folded into the constant). A rough figure, on the 2-core machine of
//! docs/performance.md §6; the rotating wheel costs more per wheel sub-step.

/// Wall time of one DOF sub-step of the explicit passage (s), contact step included; an
/// estimate. Basis (docs/performance.md §6, 2 cores): the default model, 2,093 contact steps ×
/// (25 × 152,358 track + 39 × 36,331 wheel) DOF sub-steps in 418.6 s wall, 3.8e-8 s; the small
/// test track, 2,093 × (20 × 21,144 + 24 × 17,645) in 93.1 s, 5.3e-8 s. Rounded up.
pub(crate) const SECONDS_PER_DOF_SUBSTEP: f64 = 6e-8;

/// Peak memory of the explicit path per DOF (bytes); an estimate. Basis: 1.53 GB for the
/// default model's 188,689 DOFs (docs/performance.md §6), 8.1 kB per DOF.
pub const BYTES_PER_DOF: f64 = 8.1e3;

/// The longest estimated explicit passage accepted (s): 24 hours (the default model takes
/// about 7 minutes at 140 km/h).
pub(crate) const MAX_EXPLICIT_SECONDS: f64 = 24.0 * 3600.0;

/// The estimated size of one explicit passage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExplicitEstimate {
    /// Contact steps (−).
    pub contact_steps: usize,
    /// Track and wheel sub-steps per contact step (−).
    pub substeps: [usize; 2],
    /// Track and wheel DOFs (−).
    pub dofs: [usize; 2],
    /// Estimated wall time (s).
    pub seconds: f64,
    /// Estimated peak memory (bytes).
    pub memory_bytes: f64,
}

impl ExplicitEstimate {
    /// The estimate of `contact_steps` contact steps of `substeps` sub-steps of structures of
    /// `dofs` DOFs.
    pub fn new(contact_steps: usize, substeps: [usize; 2], dofs: [usize; 2]) -> Self {
        let per_step = substeps[0] as f64 * dofs[0] as f64 + substeps[1] as f64 * dofs[1] as f64;
        ExplicitEstimate {
            contact_steps,
            substeps,
            dofs,
            seconds: contact_steps as f64 * per_step * SECONDS_PER_DOF_SUBSTEP,
            memory_bytes: (dofs[0] + dofs[1]) as f64 * BYTES_PER_DOF,
        }
    }

    /// Whether it is within `MAX_EXPLICIT_SECONDS`.
    pub(crate) fn within_bound(&self) -> bool {
        self.seconds <= MAX_EXPLICIT_SECONDS
    }
}

/// `s` seconds as `1 h 02 min`, `3 min 05 s` or `12 s`.
pub(crate) fn duration_text(s: f64) -> String {
    if !s.is_finite() {
        return "an unbounded time".into();
    }
    let r = s.round() as u64;
    match r {
        0..=59 => format!("{r} s"),
        60..=3599 => format!("{} min {:02} s", r / 60, r % 60),
        _ if s < 1e6 * 3600.0 => format!("{} h {:02} min", r / 3600, (r % 3600) / 60),
        _ => format!("{:.2e} h", s / 3600.0),
    }
}

impl std::fmt::Display for ExplicitEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "about {} wall and {:.2} GB ({} contact steps × ({} track sub-steps × {} DOFs + {} wheel sub-steps × {} DOFs) at about {SECONDS_PER_DOF_SUBSTEP:.0e} s per DOF sub-step, measured on 2 cores)",
            duration_text(self.seconds),
            self.memory_bytes / 1e9,
            self.contact_steps,
            self.substeps[0],
            self.dofs[0],
            self.substeps[1],
            self.dofs[1],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{duration_text, ExplicitEstimate};
    /// The default model's measured passage (docs/performance.md §6) is estimated within a
    /// factor 2 of its 418.6 s and accepted; a 1e-10 s step on it is far beyond the bound.
    #[test]
    fn default_model_estimate_and_a_tiny_step() {
        let e = ExplicitEstimate::new(2093, [25, 39], [152_358, 36_331]);
        assert!(
            e.seconds > 418.6 && e.seconds < 2.0 * 418.6,
            "{}",
            e.seconds
        );
        assert!(e.within_bound());
        // 16.1 µs contact step over 1e-10 s
        let tiny = ExplicitEstimate::new(2093, [161_000, 161_000], [152_358, 36_331]);
        assert!(!tiny.within_bound());
        assert!(tiny.to_string().contains(" h "), "{tiny}");
        assert_eq!(duration_text(65.0), "1 min 05 s");
        assert_eq!(duration_text(3725.0), "1 h 02 min");
    }
}
