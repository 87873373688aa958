//! Static check of the track's longitudinal compliance: how far the rail gives along x under
//! a braking/traction force at the contact (docs/theory.md §3.2).
//!
//! A wheel load `P` (N, down, along the contact normal) and a longitudinal force `Q` (N, +x,
//! on the rail) are applied together at one position of the rail's running-surface contact
//! line (the same lateral weights and plane interpolation as the passage,
//! [`line_load_vector`]), and `K u = f` is solved statically on the free DOFs of the track.
//! Reported is the longitudinal displacement of the rail head, web and foot (area-weighted
//! node means over each part of the section, as in mode classification) a distance ahead of
//! the load (+x), linearly interpolated between node planes — under the combined load and
//! under the longitudinal force alone (near the load the vertical load's bending moves the
//! head along x by a comparable amount) — and the vertical deflection of the section centroid
//! at the load.
//!
//! What it shows: how much the fastening model resists longitudinal motion. A continuous
//! rigid x-hold (RPM2) lets the head move only by shear of the section; one held column per
//! sleeper (RPM3) lets the rail slide between the columns; an elastic hold of stiffness k per
//! fastening adds a rail-wide translation of order `Q/(n k)` (n fastenings sharing the load).

use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::eigen::classify::TrackClassifier;
use crate::model::Model;
use crate::structure::TrackStructure;

use super::reduced::{line_load_vector, ContactFrame, RailContactLine};
use super::residual::StiffnessFactor;
use super::DynamicsError;

/// The load case of the check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ComplianceLoad {
    /// Vertical (normal) wheel load on the rail, pushing down (N). Default 100 kN.
    pub vertical_n: f64,
    /// Longitudinal force on the rail along +x (N). Default 15 kN.
    pub longitudinal_n: f64,
    /// Load position along the rail (m); `None`: mid-track (mid-span for an even bay count).
    pub x_m: Option<f64>,
    /// Distance ahead of the load (+x) where displacements are reported (m). Default 0.1.
    pub ahead_m: f64,
}

impl Default for ComplianceLoad {
    fn default() -> Self {
        ComplianceLoad {
            vertical_n: 100e3,
            longitudinal_n: 15e3,
            x_m: None,
            ahead_m: 0.1,
        }
    }
}

/// The result of one check (displacements in m, +x along the rail, w positive up).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LongitudinalCompliance {
    /// Load position (m).
    pub x_load_m: f64,
    /// Report position (m).
    pub x_probe_m: f64,
    /// Mean u_x of the head nodes at the report position (m).
    pub head_m: f64,
    /// Mean u_x of the web nodes (m).
    pub web_m: f64,
    /// Mean u_x of the foot nodes (m).
    pub foot_m: f64,
    /// Area-weighted mean u_x of the section at the load (m).
    pub mean_at_load_m: f64,
    /// Centroid vertical displacement at the load (m, negative = down).
    pub vertical_at_load_m: f64,
    /// u_x of head, web and foot at the report position under the longitudinal force alone
    /// (m): the part the fastening's longitudinal hold resists.
    pub longitudinal_only_m: [f64; 3],
}

/// Runs the check on a built track structure of `m` (see the module docs).
pub fn longitudinal_compliance(
    m: &Model,
    track: &TrackStructure,
    load: &ComplianceLoad,
) -> Result<LongitudinalCompliance, DynamicsError> {
    let (mats, _) = track.assemble()?;
    let frame = ContactFrame::for_inclination(m.rail.inclination);
    let hertz = super::setup::static_hertz(m, load.vertical_n)?;
    let n = track.dofmap.n_free();
    let line = RailContactLine::new(track, &Mat::zeros(n, 0), &frame, hertz.b_m)?;
    let length = track.layout.length;
    let x_load = load.x_m.unwrap_or(0.5 * length);
    let x_probe = x_load + load.ahead_m;
    for (what, x) in [("load", x_load), ("report point", x_probe)] {
        if !(0.0..=length).contains(&x) {
            return Err(DynamicsError::ComplianceOffRail {
                what,
                x_m: x,
                length_m: length,
            });
        }
    }
    // Two load cases on one factorisation: the combined load, and the longitudinal force alone
    // (near the load the vertical load's bending moves the head along x as well; the second
    // case isolates what the fastening's longitudinal hold resists).
    let mut rhs = Mat::<f64>::zeros(n, 2);
    for (col, force) in [
        [load.longitudinal_n, 0.0, -load.vertical_n],
        [load.longitudinal_n, 0.0, 0.0],
    ]
    .into_iter()
    .enumerate()
    {
        let f = line_load_vector(track, &line, &frame, x_load, force)?;
        for (i, v) in f.into_iter().enumerate() {
            rhs[(i, col)] = v;
        }
    }
    let factor = StiffnessFactor::new(mats.k.as_ref())?;
    let mut ws = factor.workspace(2);
    factor.solve_in_place(rhs.as_mut(), &mut ws);
    let classifier = TrackClassifier::new(track)?;
    let mut sections = Vec::with_capacity(2);
    for col in 0..2 {
        let u: Vec<f64> = (0..n).map(|i| rhs[(i, col)]).collect();
        let u_full = track.dofmap.expand(&u)?;
        sections.push(classifier.section_motion(&u_full)?);
    }
    let at = |planes: &[crate::eigen::classify::SectionMotion], x: f64| {
        let (p, s) = line.locate(x).expect("checked on the rail");
        let (a, b) = (&planes[p], &planes[p + 1]);
        let lerp = |va: f64, vb: f64| (1.0 - s) * va + s * vb;
        [
            lerp(a.x_head, b.x_head),
            lerp(a.x_web, b.x_web),
            lerp(a.x_foot, b.x_foot),
            lerp(a.x_mean, b.x_mean),
            lerp(a.w, b.w),
        ]
    };
    let probe = at(&sections[0], x_probe);
    let here = at(&sections[0], x_load);
    let alone = at(&sections[1], x_probe);
    Ok(LongitudinalCompliance {
        x_load_m: x_load,
        x_probe_m: x_probe,
        head_m: probe[0],
        web_m: probe[1],
        foot_m: probe[2],
        mean_at_load_m: here[3],
        vertical_at_load_m: here[4],
        longitudinal_only_m: [alone[0], alone[1], alone[2]],
    })
}

#[cfg(test)]
mod tests {
    use super::{
        longitudinal_compliance, ComplianceLoad, LongitudinalCompliance, Model, TrackStructure,
    };
    fn short(extra: &[&str]) -> Model {
        crate::model::test_problems::small_model(extra).unwrap()
    }

    fn check(m: &Model) -> LongitudinalCompliance {
        let t = TrackStructure::build(m).unwrap();
        longitudinal_compliance(m, &t, &ComplianceLoad::default()).unwrap()
    }

    /// Closed form: a rail held along x only by soft continuous springs (k per fastening, no
    /// longitudinal pad) translates as a whole by u = Q/(n k) under the longitudinal force Q
    /// (n fastenings); the section's own deformation is micrometres against millimetres.
    #[test]
    fn soft_elastic_x_hold_lets_the_rail_translate_by_q_over_n_k() {
        let k = 1e6;
        let m = short(&[
            "fastening.model=RPM2",
            "fastening.hold=\"elastic\"",
            "fastening.hold_stiffness=1e6",
            "fastening.hold_directions=[\"x\"]",
        ]);
        let r = check(&m);
        let want = 15e3 / (m.track.bays as f64 * k);
        println!("{r:?}, closed form {want:e} m");
        for (part, u) in [("head", r.head_m), ("web", r.web_m), ("foot", r.foot_m)] {
            assert!(
                (u - want).abs() < 0.01 * want,
                "{part}: {u:e} vs {want:e} m"
            );
        }
        assert!(r.vertical_at_load_m < 0.0, "the wheel load pushes down");
    }

    /// Behavioural (an ordering, no closed form): under the longitudinal force alone the rail
    /// moves along +x, with the force, the head more than the foot (shear of the section), and
    /// one held column per sleeper (RPM3) is more compliant than a continuous rigid x-hold
    /// (RPM2). 0.1 m ahead of the load the section's shear dominates, so the difference is
    /// modest (measured on this model: head 7.6 vs 7.1 µm, foot 0.76 vs 0.61 µm).
    #[test]
    fn one_held_column_is_more_compliant_than_a_continuous_rigid_x_hold() {
        let r2 = check(&short(&["fastening.model=RPM2"]));
        let r3 = check(&short(&["fastening.model=RPM3"]));
        println!("RPM2 {r2:?}\nRPM3 {r3:?}");
        let ([h2, _, f2], [h3, _, f3]) = (r2.longitudinal_only_m, r3.longitudinal_only_m);
        for (h, f) in [(h2, f2), (h3, f3)] {
            assert!(f > 0.0 && h > f, "head {h:e}, foot {f:e}");
        }
        assert!(h3 > h2 * 1.02, "head {h3:e} vs {h2:e}");
        assert!(f3 > f2 * 1.1, "foot {f3:e} vs {f2:e}");
        // An elastic x-hold of 1e9 N/m per fastening adds a translation of the rail on its
        // holds: more compliant than the rigid column it replaces.
        let e3 = check(&short(&[
            "fastening.model=RPM3",
            "fastening.hold=\"elastic\"",
            "fastening.hold_stiffness=1e9",
            "fastening.hold_directions=[\"x\"]",
        ]));
        println!("RPM3 elastic 1e9 {e3:?}");
        assert!(e3.longitudinal_only_m[2] > 2.0 * f3, "{e3:?}");
    }
}
