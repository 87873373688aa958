//! The fe-patch's split beside the explicit engine's one-step compliance (docs/theory.md §8.6,
//! "The fe-patch on the explicit engine").
//!
//! With `contact.influence = "fe-patch"` the contact's operators carry the split as a negative
//! uniform compliance `−T` (the global meshes' share of the local compliance, the twins of
//! §6.9). The reduced engine has the global model's static compliance at the contact beside
//! it, which exceeds `T`. The explicit engine has only the structures' response over one
//! contact step `G` (less the removed element-scale variation `Δg`): along x it is smaller
//! than `T` (the twins' x-compliance includes the head's wind-up over the segment, which takes
//! longer than a 16 µs step to build), and `G − Δg − T < 0` makes the operator indefinite.
//!
//! The rule: the contact keeps, implicitly, the uniform compliance `max(G − Δg − T, 0)`; the
//! rest `L = max(T + Δg − G, 0)` acts one contact step late: `+L F_n` in the approach (for
//! `−L F_{n+1}`) and `−L (F_n − F_{n−1})` in the rigid slip of the step (for
//! `−L (F_{n+1} − F_n)`). In steady rolling it is exact; in transient rolling its error is of
//! first order in the step on `L` alone. The mesh itself builds its share of the local
//! compliance over the steps that follow, which the lagged term stands beside.
//!
//! Assumptions: linear in the force (the uniform compliance is); the lagged term's loop gain
//! `L / (C_patch + c)` below 1 (`C_patch` the refined kernel's compliance of the patch), which
//! the refined kernel, carrying the same segment flexibility as the twins, keeps.

/// The series compliance one explicit contact step sets and the part of the split it lags.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SplitStep {
    /// The series compliance to set on the contact (m/N; x, y, normal): the step's `G − Δg`
    /// (already clamped at 0), raised where the operators' uniform term would make the sum
    /// negative, so that the sum is `max(G − Δg − T, 0)`.
    pub series: [f64; 3],
    /// The lagged compliance `L` (m/N; x, y, normal), ≥ 0: zero where the step carries the
    /// whole split (and always on the half-space, whose uniform term is 0).
    pub lag: [f64; 3],
}

impl SplitStep {
    /// The step's series compliance `series_c` (m/N, ≥ 0) beside the operators' uniform
    /// compliance `uniform` (m/N; `−T` ≤ 0 on the fe-patch, 0 on the half-space).
    pub(crate) fn new(series_c: [f64; 3], uniform: [f64; 3]) -> Self {
        let mut series = series_c;
        let mut lag = [0.0; 3];
        for d in 0..3 {
            let sum = series_c[d] + uniform[d];
            if sum < 0.0 {
                series[d] = -uniform[d];
                lag[d] = -sum;
            }
        }
        SplitStep { series, lag }
    }

    /// The lagged term's shifts of the contact's inputs for the forces `f` (the last, `F_n`)
    /// and `f_prev` (`F_{n−1}`) (N; x, y, normal, as the contact returns them) on a step of
    /// rigid travel `dx` (m): `(Δξ, Δη, Δδ)`, the creepages' (−) and the approach's (m).
    pub(crate) fn shifts(&self, f: [f64; 3], f_prev: [f64; 3], dx: f64) -> (f64, f64, f64) {
        let l = self.lag;
        (
            -l[0] * (f[0] - f_prev[0]) / dx,
            -l[1] * (f[1] - f_prev[1]) / dx,
            l[2] * f[2],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::SplitStep;
    use crate::contact::{
        HertzGridParams, Longitudinal, NormalInput, StepInputs, TransientConfig, TransientRolling,
    };

    /// The rule keeps the sum of the implicit and the lagged compliance equal to the step's
    /// `G − Δg − T` (by hand) and never sets a negative sum.
    #[test]
    fn the_split_keeps_the_total_and_a_non_negative_implicit_part() {
        let s = SplitStep::new([3.0e-10, 1.0e-9, 0.0], [-9.5e-10, -4.0e-10, -2.0e-10]);
        for d in 0..3 {
            let total = [3.0e-10, 1.0e-9, 0.0][d] + [-9.5e-10, -4.0e-10, -2.0e-10][d];
            let implicit = s.series[d] + [-9.5e-10, -4.0e-10, -2.0e-10][d];
            assert!(implicit >= 0.0, "{d}");
            assert!((implicit - s.lag[d] - total).abs() < 1e-24, "{d}");
        }
        assert_eq!(s.lag, [6.5e-10, 0.0, 2.0e-10]);
        // the half-space: nothing changes
        let h = SplitStep::new([3.0e-10, 0.0, 1.0e-10], [0.0; 3]);
        assert_eq!((h.series, h.lag), ([3.0e-10, 0.0, 1.0e-10], [0.0; 3]));
    }

    /// A contact with the uniform compliance `c` solved implicitly against the same
    /// compliance split into an implicit `c + L` and a lagged `−L` (the shifts of
    /// [`SplitStep::shifts`]), under a creepage and an approach that vary over about 60 steps:
    /// the lagged contact follows the implicit one (the independent reference) within 2 % of
    /// the forces' range, and the difference halves when the step halves (first order).
    #[test]
    fn the_lagged_part_follows_the_implicit_contact_to_first_order_in_the_step() {
        let (c, l) = ([4.0e-10, 4.0e-10, 2.0e-10], [3.0e-10, 3.0e-10, 1.5e-10]);
        let run = |nx: usize, lagged: bool| -> Vec<[f64; 2]> {
            let cfg = TransientConfig::around_hertz(&HertzGridParams {
                friction: 0.3,
                nx,
                ny: 12,
                margin: 1.4,
                ..HertzGridParams::default()
            })
            .unwrap();
            let mut k = TransientRolling::new(cfg).unwrap();
            let cs = if lagged {
                [0, 1, 2].map(|d| c[d] + l[d])
            } else {
                c
            };
            k.set_series_compliance(cs).unwrap();
            let split = SplitStep {
                series: cs,
                lag: if lagged { l } else { [0.0; 3] },
            };
            let dt = k.time_step_s();
            let dx = 38.9 * dt;
            // the forcing: one period over 0.06 m of travel (60 steps at nx 20)
            let period = 0.06;
            let (mut f, mut f_prev) = ([0.0; 3], [0.0; 3]);
            let mut out = Vec::new();
            let delta0 = 1.0e-4;
            let steps = (2.0 * period / dx).round() as usize;
            for n in 0..steps {
                let x = n as f64 * dx;
                let s = (2.0 * std::f64::consts::PI * x / period).sin();
                let (dxi, deta, dd) = split.shifts(f, f_prev, dx);
                let r = k
                    .step(&StepInputs {
                        normal: NormalInput::Approach(delta0 * (1.0 + 0.2 * s) + dd),
                        longitudinal: Longitudinal::Creepage(1.0e-3 * (1.0 + s) + dxi),
                        lateral_creepage: deta,
                        spin_per_m: 0.0,
                        rail_height_m: None,
                    })
                    .unwrap();
                f_prev = f;
                f = [r.fx_n, r.fy_n, r.normal_force_n];
                out.push([r.fx_n, r.normal_force_n]);
            }
            out
        };
        let gap = |nx: usize| -> [f64; 2] {
            let (a, b) = (run(nx, false), run(nx, true));
            // after the first quarter period (the start from zero force)
            let skip = a.len() / 8;
            [0, 1].map(|q| {
                let range = a[skip..]
                    .iter()
                    .map(|v| v[q])
                    .fold(f64::NEG_INFINITY, f64::max)
                    - a[skip..].iter().map(|v| v[q]).fold(f64::INFINITY, f64::min);
                a[skip..]
                    .iter()
                    .zip(&b[skip..])
                    .map(|(u, v)| (u[q] - v[q]).abs())
                    .fold(0.0, f64::max)
                    / range
            })
        };
        let (g1, g2) = (gap(20), gap(40));
        for q in 0..2 {
            assert!(g1[q] < 0.02 && g1[q] > 0.0, "{q}: {g1:?}");
            let ratio = g1[q] / g2[q];
            assert!((1.5..=2.5).contains(&ratio), "{q}: {g1:?} {g2:?}");
        }
    }
}
