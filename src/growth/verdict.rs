//! The plain-language verdict of a trial-amplitude growth (docs/theory.md §10.4): what the
//! model found, in words, for the top of a report and the last lines a command prints.
//!
//! Four outcomes:
//! - **no initiation**: the smooth-rail passage leaves no wear component in the 20–80 mm band,
//!   so there is no trial corrugation to grow;
//! - **decays**: the smallest trial amplitude does not grow consistently (there is no
//!   limiting amplitude; the phase of the new wear says why);
//! - **grows to a limiting amplitude**: the smaller amplitudes grow consistently, a larger one
//!   does not; `(2A_max)_l` is the largest of the growing run;
//! - **grows through the range**: every amplitude tried grows consistently, so no limiting
//!   amplitude was found within it (not "grows without limit": larger amplitudes were not
//!   tried).
//!
//! The verdict also names the strongest wear component of the smooth rail (wavelength and
//! frequency) and the mode nearest to it, and, when given, the smooth rail's relative wear
//! against the initiation threshold. Figures are rounded to 3 (wavelengths, percentages) or 4
//! (frequencies, amplitudes) significant digits.

use serde::Serialize;

use super::procedure::{ModeLines, TrialGrowth};
use super::PhaseRelation;
use crate::dynamics::coupled::{ModeAttribution, ATTRIBUTION_WINDOW};

/// One trial amplitude as the verdict needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrialOutcome {
    /// Peak-to-trough 2A_max (µm).
    pub amplitude_um: f64,
    /// Growing phase and at least one reference component in Case 1 or Case 2.
    pub grows_consistently: bool,
    /// Phase of the new wear relative to the corrugation.
    pub relation: PhaseRelation,
}

/// The mode nearest to a frequency.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NearestMode {
    /// Which family: e.g. "wheel", "longitudinal compression", "vertical bending".
    pub family: String,
    /// Its eigenfrequency (Hz).
    pub frequency_hz: f64,
    /// Relative difference |f − f_mode| / f_mode of the component from it (−).
    pub difference: f64,
}

/// The mode of `families` (name, eigenfrequencies in Hz) nearest to `f_hz` (Hz) in relative
/// difference; `None` when every list is empty.
pub(crate) fn nearest_mode(f_hz: f64, families: &[(&str, &[f64])]) -> Option<NearestMode> {
    families
        .iter()
        .flat_map(|(name, fs)| fs.iter().map(move |&m| (*name, m)))
        .filter(|(_, m)| *m > 0.0 && m.is_finite())
        .map(|(name, m)| NearestMode {
            family: name.to_string(),
            frequency_hz: m,
            difference: (f_hz - m).abs() / m,
        })
        .min_by(|a, b| a.difference.total_cmp(&b.difference))
}

/// The smooth rail's relative wear against the initiation threshold.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct InitiationCheck {
    /// Band RMS of the differential wear / its mean (−); `None` when the mean is not positive.
    pub relative_wear: Option<f64>,
    /// The threshold (−), `wear.initiation_threshold`.
    pub threshold: f64,
    /// Whether the whole initiation criterion holds (relative wear and the F_L match).
    pub initiates: bool,
}

/// What the verdict is about.
#[derive(Clone, Copy, Debug)]
pub struct VerdictInput<'a> {
    /// Train speed (km/h).
    pub speed_kmh: f64,
    /// The trial amplitudes (any order).
    pub trials: &'a [TrialOutcome],
    /// Strongest smooth-rail wear component: (wavelength mm, frequency Hz).
    pub strongest_wear: Option<(f64, f64)>,
    /// The uncoupled eigenfrequency (wheel, LC, VB) nearest to the strongest wear component.
    pub nearest_mode: Option<&'a NearestMode>,
    /// The coupled wheel–track mode the strongest wear component is attributed to
    /// (docs/theory.md §7.10), when the coupled modes were computed.
    pub coupled: Option<&'a ModeAttribution>,
    /// The initiation check of the smooth rail, when evaluated.
    pub initiation: Option<InitiationCheck>,
}

/// The outcome class of the verdict (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "outcome")]
pub enum Outcome {
    /// No wear component on the smooth rail: nothing to grow.
    NoInitiation,
    /// The smallest trial amplitude does not grow consistently.
    Decays,
    /// Growth up to `limiting_amplitude_um`, not at `next_amplitude_um` (µm).
    GrowsToLimit {
        /// (2A_max)_l (µm).
        limiting_amplitude_um: f64,
        /// The next larger amplitude tried, which does not grow consistently (µm).
        next_amplitude_um: f64,
    },
    /// Every amplitude tried grows consistently, the largest being `largest_tried_um` (µm).
    GrowsThroughRange {
        /// The largest amplitude tried (µm).
        largest_tried_um: f64,
    },
    /// The smallest trial's passage failed, so no trial was evaluated.
    NotEvaluated {
        /// The smallest trial amplitude, whose passage failed (µm).
        failed_amplitude_um: f64,
    },
}

/// The verdict: its outcome and its sentences (the first is the headline).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Verdict {
    /// The outcome class.
    pub outcome: Outcome,
    /// Sentences, the headline first.
    pub lines: Vec<String>,
}

impl Verdict {
    /// All sentences as one paragraph.
    pub fn text(&self) -> String {
        self.lines.join(" ")
    }
}

/// `v` rounded to `digits` significant digits, printed without an exponent for
/// 1e-4 ≤ |v| < 1e7 and without trailing decimals beyond the rounding.
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let digits = digits.max(1);
    let mag = v.abs().log10().floor() as i32;
    if !(-4..7).contains(&mag) {
        return format!("{:.*e}", digits - 1, v);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    let scale = 10f64.powi(digits as i32 - 1 - mag);
    let r = (v * scale).round() / scale;
    format!("{r:.decimals$}")
}

/// `s` without trailing decimal zeros ("1.00" → "1", "2.50" → "2.5").
pub fn trim_zeros(s: &str) -> String {
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

fn amp(a: f64) -> String {
    format!("{} µm", trim_zeros(&sig(a, 4)))
}

fn amp_list(v: &[f64]) -> String {
    v.iter()
        .map(|&a| trim_zeros(&sig(a, 4)))
        .collect::<Vec<_>>()
        .join(", ")
        + " µm"
}

/// Why the smallest amplitude does not grow: the phases of the trials, in words.
fn decay_reason(trials: &[TrialOutcome]) -> String {
    let count = |r: PhaseRelation| trials.iter().filter(|t| t.relation == r).count();
    let (inp, ind) = (
        count(PhaseRelation::InPhase),
        count(PhaseRelation::Indeterminate),
    );
    let n = trials.len();
    if inp == n {
        return "every trial corrugation decays (the new wear is in phase with it)".into();
    }
    let mut parts = Vec::new();
    if inp > 0 {
        parts.push(format!(
            "{inp} of {n} trial corrugations decay (new wear in phase with them)"
        ));
    }
    if ind > 0 {
        parts.push(format!(
            "{ind} of {n} have a phase too weak to call (|r| < 0.2)"
        ));
    }
    let anti_inconsistent = trials
        .iter()
        .filter(|t| t.relation == PhaseRelation::AntiPhase && !t.grows_consistently)
        .count();
    if anti_inconsistent > 0 {
        parts.push(format!(
            "{anti_inconsistent} of {n} are in anti-phase but their wavelengths do not match the trial corrugation's (grey)"
        ));
    }
    if parts.is_empty() {
        "the smallest trial corrugation does not grow consistently".into()
    } else {
        parts.join("; ")
    }
}

/// Builds the verdict (module doc) of `input`.
pub fn verdict(input: &VerdictInput<'_>) -> Verdict {
    let mut trials = input.trials.to_vec();
    trials.sort_by(|a, b| a.amplitude_um.total_cmp(&b.amplitude_um));
    let at = format!(
        "on this track at {} km/h",
        trim_zeros(&sig(input.speed_kmh, 4))
    );
    let (outcome, headline) = match (input.strongest_wear, trials.first()) {
        (None, _) | (_, None) => (
            Outcome::NoInitiation,
            format!(
                "No corrugation initiates {at}: the smooth-rail passage leaves no wear component \
                 in the 20–80 mm band, so there is no trial corrugation to grow."
            ),
        ),
        (Some(_), Some(first)) if !first.grows_consistently => {
            let mut h = format!("No consistent growth {at}: {}", decay_reason(&trials));
            let later: Vec<f64> = trials
                .iter()
                .filter(|t| t.grows_consistently)
                .map(|t| t.amplitude_um)
                .collect();
            if !later.is_empty() {
                h.push_str(&format!(
                    "; only the larger trial corrugations of {} grow consistently, not the \
                     smallest, so small initial corrugation does not grow",
                    amp_list(&later)
                ));
            }
            h.push('.');
            (Outcome::Decays, h)
        }
        (Some(_), Some(_)) => {
            let run = trials.iter().take_while(|t| t.grows_consistently).count();
            if run == trials.len() {
                let largest = trials[run - 1].amplitude_um;
                (
                    Outcome::GrowsThroughRange {
                        largest_tried_um: largest,
                    },
                    format!(
                        "Corrugation grows consistently {at} at every trial amplitude up to {}: \
                         no limiting amplitude was found within the amplitudes tried (larger \
                         ones were not tried).",
                        amp(largest)
                    ),
                )
            } else {
                let (l, next) = (trials[run - 1].amplitude_um, trials[run].amplitude_um);
                (
                    Outcome::GrowsToLimit {
                        limiting_amplitude_um: l,
                        next_amplitude_um: next,
                    },
                    format!(
                        "Corrugation grows consistently {at} up to the limiting amplitude \
                         (2A_max)_l = {} peak-to-trough; at {} it no longer grows consistently.",
                        amp(l),
                        amp(next)
                    ),
                )
            }
        }
    };
    let mut lines = vec![headline];
    if let Some((wl, f)) = input.strongest_wear {
        let mut s = format!(
            "Strongest wear component {} mm / {} Hz",
            sig(wl, 3),
            sig(f, 4)
        );
        if let Some(a) = input.coupled {
            let (part, share) = a.shares.dominant();
            if a.is_distant() {
                s.push_str(&format!(
                    "; no coupled wheel–track mode within {} % (the nearest the contact sees, {} Hz, \
                     {} % away, has most of its energy in the {part}: {} %)",
                    sig(100.0 * ATTRIBUTION_WINDOW, 2),
                    sig(a.mode_frequency_hz, 4),
                    sig(100.0 * a.relative_offset(), 2),
                    sig(100.0 * share, 2)
                ));
            } else {
                s.push_str(&format!(
                    "; coupled wheel–track mode {} Hz, most of its energy in the {part} ({} %)",
                    sig(a.mode_frequency_hz, 4),
                    sig(100.0 * share, 2)
                ));
            }
        }
        let uncoupled = if input.coupled.is_some() {
            "nearest uncoupled eigenfrequency"
        } else {
            "nearest mode"
        };
        match input.nearest_mode {
            Some(m) => s.push_str(&format!(
                "; {uncoupled}: {}, {} Hz ({} % away).",
                m.family,
                sig(m.frequency_hz, 4),
                sig(100.0 * m.difference, 2)
            )),
            None => s.push_str("; no mode of the bases to compare with."),
        }
        lines.push(s);
    }
    if let Some(c) = input.initiation {
        let t = format!("{} %", trim_zeros(&sig(100.0 * c.threshold, 3)));
        lines.push(match c.relative_wear {
            None => format!(
                "Initiation criterion: the smooth rail has no positive mean wear (threshold {t})."
            ),
            Some(r) => format!(
                "Initiation criterion: smooth-rail wear band RMS / mean {} % against the \
                 threshold {t} (wear.initiation_threshold): {}.",
                sig(100.0 * r, 3),
                match (r >= c.threshold, c.initiates) {
                    (false, _) => "below it, so by this criterion the smooth rail does not initiate corrugation",
                    (true, true) => "at or above it, and F_L follows the wear: the smooth rail initiates corrugation",
                    (true, false) => "at or above it, but F_L's dominant wavelength does not follow the wear's, so it does not initiate",
                }
            ),
        });
    }
    Verdict { outcome, lines }
}

/// The consistency case in words: "Case 1", "Case 2" or "none".
pub fn case_label(c: super::ConsistencyCase) -> &'static str {
    match c {
        super::ConsistencyCase::Case1 => "Case 1",
        super::ConsistencyCase::Case2 => "Case 2",
        super::ConsistencyCase::None => "none",
    }
}

/// The colour of a consistency class in the reports' HTML tables (CSS), keyed by
/// [`class_label`]'s words: light green, dark green, grey; `None` for other text.
pub fn class_colour(label: &str) -> Option<&'static str> {
    match label {
        "light green" => Some("#c8f0c8"),
        "dark green" => Some("#6fbf6f"),
        "grey" => Some("#d0d0d0"),
        _ => None,
    }
}

/// The consistency class in words: "light green", "dark green" or "grey".
pub fn class_label(c: super::ConsistencyClass) -> &'static str {
    match c {
        super::ConsistencyClass::LightGreen => "light green",
        super::ConsistencyClass::DarkGreen => "dark green",
        super::ConsistencyClass::Grey => "grey",
    }
}

/// The legend of the consistency table (docs/theory.md §10.2–§10.4), for reports.
pub const CONSISTENCY_LEGEND: &str = "How to read the table: for each reference wavelength λ_ref (a wear component of the smooth rail) the nearest spectral peak of W_f, F_L and F_N of the passage over the trial corrugation is matched; the percentage after each is its relative deviation |λ − λ_ref| / λ_ref. A signal is consistent when its deviation is at most 3 %. Case 1: all three signals consistent; Case 2: exactly two; otherwise none. Class: light green = Case 1 or 2 with every consistent signal within 1 % (strong); dark green = Case 1 or 2 with a consistent signal between 1 % and 3 % (weaker); grey = inconsistent. A trial amplitude grows consistently when the new wear is in anti-phase with the corrugation (correlation r ≤ −0.2: it deepens the troughs) and at least one reference is in Case 1 or 2.";

/// The mode families of `modes` by name, for `nearest_mode`.
pub fn families(modes: &ModeLines) -> [(&'static str, &[f64]); 3] {
    [
        ("wheel", &modes.wheel_hz),
        ("longitudinal compression", &modes.longitudinal_hz),
        ("vertical bending", &modes.vertical_hz),
    ]
}

/// The verdict of the trial-amplitude growth `g` at `speed_kmh` (km/h): its strongest
/// smooth-rail wear component, the coupled mode it is attributed to (`coupled`, when the
/// coupled modes were computed), the uncoupled eigenfrequency of `modes` nearest to it, and
/// `initiation` when given.
pub fn growth_verdict(
    g: &TrialGrowth,
    speed_kmh: f64,
    modes: &ModeLines,
    initiation: Option<InitiationCheck>,
    coupled: Option<&ModeAttribution>,
) -> Verdict {
    let trials: Vec<TrialOutcome> = g
        .amplitudes
        .iter()
        .map(|a| TrialOutcome {
            amplitude_um: a.amplitude_um,
            grows_consistently: a.grows_consistently,
            relation: a.phase.relation,
        })
        .collect();
    let strongest = g
        .smooth
        .dominant_wavelength_mm
        .zip(g.smooth.dominant_frequency_hz);
    let near = strongest.and_then(|(_, f)| nearest_mode(f, &families(modes)));
    let mut v = verdict(&VerdictInput {
        speed_kmh,
        trials: &trials,
        strongest_wear: strongest,
        nearest_mode: near.as_ref(),
        coupled,
        initiation,
    });
    if let (Some(s), true) = (&g.stopped, g.amplitudes.is_empty()) {
        // Without an evaluated trial the verdict's own headline ("no wear component") is
        // wrong: the smooth rail had one, but no trial passage could run.
        v.outcome = Outcome::NotEvaluated {
            failed_amplitude_um: s.amplitude_um,
        };
        v.lines[0] = format!(
            "Growth not evaluated on this track at {} km/h: the passage over the smallest \
             trial corrugation ({}) failed, so no trial corrugation was evaluated.",
            trim_zeros(&sig(speed_kmh, 4)),
            amp(s.amplitude_um)
        );
    }
    if let Some(s) = &g.stopped {
        v.lines.insert(
            1.min(v.lines.len()),
            format!(
                "The trial corrugation of {} and any larger ones were not evaluated: its \
                 passage failed ({}).",
                amp(s.amplitude_um),
                s.reason
            ),
        );
    }
    v
}

/// The verdict when the smooth rail leaves no wear component to grow (no trial growth ran).
pub fn no_initiation_verdict(speed_kmh: f64, initiation: Option<InitiationCheck>) -> Verdict {
    verdict(&VerdictInput {
        speed_kmh,
        trials: &[],
        strongest_wear: None,
        nearest_mode: None,
        coupled: None,
        initiation,
    })
}

#[cfg(test)]
mod tests {
    use super::{
        nearest_mode, sig, trim_zeros, verdict, InitiationCheck, ModeAttribution, NearestMode,
        Outcome, PhaseRelation, TrialOutcome, VerdictInput,
    };
    fn t(a: f64, grows: bool, r: PhaseRelation) -> TrialOutcome {
        TrialOutcome {
            amplitude_um: a,
            grows_consistently: grows,
            relation: r,
        }
    }

    fn wheel() -> NearestMode {
        nearest_mode(
            1066.3,
            &[
                ("longitudinal compression", &[2061.0, 2170.0]),
                ("wheel", &[1060.2, 1409.0]),
                ("vertical bending", &[880.0]),
            ],
        )
        .unwrap()
    }

    #[test]
    fn sig_rounds_to_significant_digits() {
        assert_eq!(sig(36.4821, 3), "36.5");
        assert_eq!(sig(1066.3, 4), "1066");
        assert_eq!(sig(0.004123, 3), "0.00412");
        assert_eq!(sig(140.0, 4), "140.0");
        assert_eq!(trim_zeros(&sig(140.0, 4)), "140");
        assert_eq!(trim_zeros("1.00e-3"), "1.00e-3");
        assert_eq!(sig(1.0, 3), "1.00");
        assert_eq!(sig(2.5e-9, 3), "2.50e-9");
        assert_eq!(sig(-12.345, 3), "-12.3");
    }

    #[test]
    fn nearest_mode_is_nearest_in_relative_difference_over_all_families() {
        let m = wheel();
        assert_eq!(m.family, "wheel");
        assert_eq!(m.frequency_hz, 1060.2);
        assert!((m.difference - 6.1 / 1060.2).abs() < 1e-12);
        assert!(nearest_mode(100.0, &[("wheel", &[])]).is_none());
    }

    /// A coupled mode with the shares `wheel_elastic`, `wheel_rigid`, `support` (the rest
    /// rail LC) at `mode_hz`, attributed to 1066.3 Hz.
    fn coupled(
        mode_hz: f64,
        wheel_elastic: f64,
        wheel_rigid: f64,
        support: f64,
    ) -> ModeAttribution {
        use crate::dynamics::coupled::ModeShares;
        let mut rail = [0.0; 8];
        rail[0] = 1.0 - wheel_elastic - wheel_rigid - support;
        ModeAttribution {
            frequency_hz: 1066.3,
            mode_frequency_hz: mode_hz,
            damping_ratio: 0.01,
            position_m: 4.8,
            dominant: String::new(),
            shares: ModeShares {
                wheel_elastic,
                wheel_rigid,
                rail,
                support,
                contact: 0.0,
            },
            rail_x_to_n: 0.1,
        }
    }

    /// The verdict names the strongest component's coupled mode by the one rule of
    /// `ModeShares::dominant` (the wheel's two parts together: 0.30 + 0.15 beat the support's
    /// 0.40), says when it lies outside the 3 % window, and keeps the uncoupled
    /// eigenfrequency beside it under its own name.
    #[test]
    fn the_verdict_names_the_coupled_mode_by_the_attribution_rule() {
        use PhaseRelation::InPhase;
        let trials = [t(10.0, false, InPhase)];
        let m = wheel();
        let near = coupled(1065.0, 0.30, 0.15, 0.40);
        let line = |a: &ModeAttribution| {
            verdict(&VerdictInput {
                speed_kmh: 140.0,
                trials: &trials,
                strongest_wear: Some((36.4821, 1066.3)),
                nearest_mode: Some(&m),
                coupled: Some(a),
                initiation: None,
            })
            .lines[1]
                .clone()
        };
        assert_eq!(
            line(&near),
            "Strongest wear component 36.5 mm / 1066 Hz; coupled wheel–track mode 1065 Hz, most \
             of its energy in the wheel (45 %); nearest uncoupled eigenfrequency: wheel, 1060 Hz \
             (0.58 % away)."
        );
        let (part, share) = near.shares.dominant();
        assert_eq!(part, "wheel");
        assert!((share - 0.45).abs() < 1e-12);
        let far = coupled(1200.0, 0.10, 0.05, 0.60);
        let l = line(&far);
        assert!(
            l.contains("no coupled wheel–track mode within 3.0 %")
                && l.contains("1200 Hz, 13 % away, has most of its energy in the support: 60 %"),
            "{l}"
        );
    }

    #[test]
    fn decaying_growth_says_so_and_names_the_component_and_mode() {
        use PhaseRelation::InPhase;
        let trials = [
            t(160.0, false, InPhase),
            t(10.0, false, InPhase),
            t(40.0, false, InPhase),
            t(80.0, false, InPhase),
        ];
        let m = wheel();
        let v = verdict(&VerdictInput {
            speed_kmh: 140.0,
            trials: &trials,
            strongest_wear: Some((36.4821, 1066.3)),
            nearest_mode: Some(&m),
            coupled: None,
            initiation: None,
        });
        assert_eq!(v.outcome, Outcome::Decays);
        assert_eq!(
            v.lines,
            vec![
                "No consistent growth on this track at 140 km/h: every trial corrugation decays \
                 (the new wear is in phase with it)."
                    .to_string(),
                "Strongest wear component 36.5 mm / 1066 Hz; nearest mode: wheel, 1060 Hz \
                 (0.58 % away)."
                    .to_string(),
            ]
        );
        assert!(!v.text().contains("limiting amplitude none"));
    }

    #[test]
    fn mixed_phases_are_counted_and_late_growth_is_named() {
        use PhaseRelation::{AntiPhase, InPhase, Indeterminate};
        let trials = [
            t(10.0, false, Indeterminate),
            t(40.0, false, InPhase),
            t(80.0, true, AntiPhase),
            t(160.0, false, AntiPhase),
        ];
        let v = verdict(&VerdictInput {
            speed_kmh: 100.0,
            trials: &trials,
            strongest_wear: Some((40.0, 694.4)),
            nearest_mode: None,
            coupled: None,
            initiation: None,
        });
        assert_eq!(v.outcome, Outcome::Decays);
        let h = &v.lines[0];
        assert!(h.contains("1 of 4 trial corrugations decay"), "{h}");
        assert!(h.contains("1 of 4 have a phase too weak to call"), "{h}");
        assert!(h.contains("1 of 4 are in anti-phase but"), "{h}");
        assert!(
            h.contains("only the larger trial corrugations of 80 µm"),
            "{h}"
        );
        assert!(v.lines[1].ends_with("no mode of the bases to compare with."));
    }

    #[test]
    fn growth_with_a_limiting_amplitude_names_it_and_the_next() {
        use PhaseRelation::{AntiPhase, InPhase};
        let trials = [
            t(10.0, true, AntiPhase),
            t(40.0, true, AntiPhase),
            t(80.0, false, InPhase),
            t(160.0, true, AntiPhase),
        ];
        let v = verdict(&VerdictInput {
            speed_kmh: 140.0,
            trials: &trials,
            strongest_wear: Some((36.5, 1066.0)),
            nearest_mode: None,
            coupled: None,
            initiation: None,
        });
        assert_eq!(
            v.outcome,
            Outcome::GrowsToLimit {
                limiting_amplitude_um: 40.0,
                next_amplitude_um: 80.0
            }
        );
        assert_eq!(
            v.lines[0],
            "Corrugation grows consistently on this track at 140 km/h up to the limiting \
             amplitude (2A_max)_l = 40 µm peak-to-trough; at 80 µm it no longer grows \
             consistently."
        );
    }

    #[test]
    fn growth_at_every_amplitude_is_not_called_unlimited() {
        use PhaseRelation::AntiPhase;
        let trials = [t(10.0, true, AntiPhase), t(160.0, true, AntiPhase)];
        let v = verdict(&VerdictInput {
            speed_kmh: 140.0,
            trials: &trials,
            strongest_wear: Some((36.5, 1066.0)),
            nearest_mode: None,
            coupled: None,
            initiation: Some(InitiationCheck {
                relative_wear: Some(0.004123),
                threshold: 0.01,
                initiates: false,
            }),
        });
        assert_eq!(
            v.outcome,
            Outcome::GrowsThroughRange {
                largest_tried_um: 160.0
            }
        );
        assert!(v.lines[0].contains("at every trial amplitude up to 160 µm"));
        assert!(v.lines[0].contains("no limiting amplitude was found within the amplitudes tried"));
        assert!(!v.lines[0].contains("without limit"));
        assert_eq!(
            v.lines[2],
            "Initiation criterion: smooth-rail wear band RMS / mean 0.412 % against the \
             threshold 1 % (wear.initiation_threshold): below it, so by this criterion the \
             smooth rail does not initiate corrugation."
        );
    }

    #[test]
    fn no_wear_component_means_no_initiation() {
        let v = verdict(&VerdictInput {
            speed_kmh: 60.0,
            trials: &[],
            strongest_wear: None,
            nearest_mode: None,
            coupled: None,
            initiation: Some(InitiationCheck {
                relative_wear: Some(0.02),
                threshold: 0.01,
                initiates: true,
            }),
        });
        assert_eq!(v.outcome, Outcome::NoInitiation);
        assert_eq!(
            v.lines[0],
            "No corrugation initiates on this track at 60 km/h: the smooth-rail passage leaves \
             no wear component in the 20–80 mm band, so there is no trial corrugation to grow."
        );
        assert!(v.lines[1].contains("at or above it, and F_L follows the wear"));
    }
}
