use super::{
    attribute, attribution_text, coupled_modes, coupled_state_modes, ContactLinearisation,
    CoordinateLabels, CoupledMode, CoupledSystem, Mat, ModalSystem, ModeShares, TrackFamily,
};
use std::f64::consts::PI;

fn sys(omega2: &[f64], damping: &[f64]) -> ModalSystem {
    let n = omega2.len();
    ModalSystem {
        omega2: omega2.to_vec(),
        damping: Mat::from_fn(n, n, |i, j| if i == j { damping[i] } else { 0.0 }),
    }
}

fn labels(n: usize) -> CoordinateLabels {
    CoordinateLabels {
        track: vec![(0.7, TrackFamily::VerticalBending); n],
    }
}

fn w(f: f64) -> f64 {
    2.0 * PI * f
}

/// With every contact term zero the coupled modes are the union of the substructures'
/// modes: for diagonal damping `c_i` each is `λ = −c_i/2 ± i√(ω_i² − c_i²/4)` (closed
/// form), and its energy lies entirely in its own substructure.
#[test]
fn zero_contact_gives_the_union_of_wheel_and_track_modes() {
    let tf = [310.0, 820.0, 1400.0];
    let wf = [0.0, 560.0, 1060.0];
    let tc = [40.0, 0.0, 120.0];
    let wc = [0.0, 3.0, 0.0];
    let track = sys(&tf.map(|f| w(f).powi(2)), &tc);
    let wheel = sys(&wf.map(|f| w(f).powi(2)), &wc);
    let rr: Vec<f64> = (0..9).map(|i| 0.1 + 0.05 * i as f64).collect();
    let wr: Vec<f64> = (0..9).map(|i| 0.2 - 0.03 * i as f64).collect();
    let s = CoupledSystem {
        track: &track,
        wheel: &wheel,
        rail_rows: &rr,
        wheel_rows: &wr,
    };
    let modes = coupled_modes(&s, &ContactLinearisation::uncoupled(30.0), &labels(3), 1.0).unwrap();
    let mut expect: Vec<(f64, f64, bool)> = Vec::new();
    for (f, c) in tf.iter().zip(tc) {
        expect.push((w(*f), c, true));
    }
    for (f, c) in wf.iter().zip(wc).skip(1) {
        expect.push((w(*f), c, false));
    }
    expect.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(modes.len(), expect.len(), "{modes:?}");
    for (m, (wn, c, is_track)) in modes.iter().zip(&expect) {
        let fd = (wn * wn - c * c / 4.0).sqrt() / (2.0 * PI);
        let zeta = c / (2.0 * wn);
        assert!((m.frequency_hz - fd).abs() < 1e-9 * fd, "{m:?} vs {fd}");
        assert!((m.damping_ratio - zeta).abs() < 1e-9, "{m:?} vs ζ {zeta}");
        if *is_track {
            assert!((m.shares.rail[TrackFamily::VerticalBending.code()] - 0.7).abs() < 1e-9);
            assert!((m.shares.support - 0.3).abs() < 1e-9);
        } else {
            assert!((m.shares.wheel_elastic - 1.0).abs() < 1e-9, "{m:?}");
        }
    }
}

/// One wheel mode on one track mode joined by a normal spring k: the undamped
/// eigenvalues of `[[ω_w² + k w², −k w r], [−k w r, ω_t² + k r²]]` (closed form).
#[test]
fn two_dof_normal_spring_is_the_closed_form() {
    let (wt2, ww2) = (w(900.0).powi(2), w(1060.0).powi(2));
    let (r, wn) = (0.031, 0.018);
    let k = 1.2e9;
    let track = sys(&[wt2], &[0.0]);
    let wheel = sys(&[ww2], &[0.0]);
    let rr = [0.0, 0.0, r];
    let wr = [0.0, 0.0, wn];
    let s = CoupledSystem {
        track: &track,
        wheel: &wheel,
        rail_rows: &rr,
        wheel_rows: &wr,
    };
    let lin = ContactLinearisation {
        normal_stiffness_n_per_m: k,
        ..ContactLinearisation::uncoupled(30.0)
    };
    let modes = coupled_modes(&s, &lin, &labels(1), 0.0).unwrap();
    let (a, d, b) = (ww2 + k * wn * wn, wt2 + k * r * r, -k * wn * r);
    let disc = ((a - d) * (a - d) / 4.0 + b * b).sqrt();
    let exact = [0.5 * (a + d) - disc, 0.5 * (a + d) + disc].map(|l| l.sqrt() / (2.0 * PI));
    assert_eq!(modes.len(), 2);
    for (m, f) in modes.iter().zip(exact) {
        assert!(
            (m.frequency_hz - f).abs() < 1e-9 * f,
            "{} vs {f}",
            m.frequency_hz
        );
        assert!(m.damping_ratio.abs() < 1e-9);
        let total: f64 = m.shares.values().iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        assert!(m.shares.contact > 0.0 && m.shares.wheel_elastic > 0.0);
    }
}

/// One track mode held at the contact in x by the creep force: with lag (Maxwell
/// element) the eigenvalues are roots of `(s² + ω²)(s + V/L) + k r² s = 0`, without it of
/// `s² + c r² s + ω² = 0` (closed forms); the wheel's rigid mode has no contact row.
#[test]
fn creep_force_with_and_without_lag_is_the_closed_form() {
    let wt2 = w(1000.0).powi(2);
    let r = 0.03;
    let track = sys(&[wt2], &[0.0]);
    let wheel = sys(&[0.0], &[0.0]);
    let rr = [r, 0.0, 0.0];
    let wr = [0.0; 3];
    let s = CoupledSystem {
        track: &track,
        wheel: &wheel,
        rail_rows: &rr,
        wheel_rows: &wr,
    };
    let v = 38.9;
    for l in [0.0, 0.004] {
        let lin = ContactLinearisation {
            creep_coefficient_n: [4.0e6, 0.0],
            relaxation_length_m: [l, 0.0],
            ..ContactLinearisation::uncoupled(v)
        };
        let modes = coupled_state_modes(&s, &lin).unwrap();
        assert_eq!(modes.len(), 1, "{l}");
        let sl = modes[0].lambda;
        let res = if l == 0.0 {
            let c = lin.creep_damping_ns_per_m(0);
            sl * sl + sl * (c * r * r) + wt2
        } else {
            let k = lin.tangential_stiffness_n_per_m(0).unwrap();
            (sl * sl + wt2) * (sl + v / l) + sl * (k * r * r)
        };
        let scale = if l == 0.0 { wt2 } else { wt2 * sl.norm() };
        // The state matrix spans ω² ≈ 4e7 and 1: eigenvalues to ~1e-8 relative.
        assert!(res.norm() < 1e-7 * scale, "L {l}: residual {res}");
        assert!(sl.re < 0.0, "the creep force damps: {sl}");
    }
}

#[test]
fn attribution_picks_the_nearest_visible_mode() {
    let mk = |f: f64, amp: f64, dom: &str| CoupledMode {
        position_m: 1.0,
        frequency_hz: f,
        damping_ratio: 0.01,
        shares: ModeShares::default(),
        dominant: dom.into(),
        contact_amplitudes_m_per_sqrt_j: [amp, 0.0, 0.0, 0.0],
        rail_x_to_n: 0.0,
    };
    let modes = [
        mk(1000.0, 1.0, "a"),
        mk(1050.0, 1e-4, "b"),
        mk(1200.0, 0.5, "c"),
        mk(1402.0, 0.01, "d"),
        mk(1430.0, 0.4, "e"),
    ];
    // 1090 Hz: no mode within 3 %, nearest visible (b is not visible) → a; 1160 → c;
    // 1400 Hz: d is nearest but e, within 3 %, moves the contact more.
    let a = attribute(&[1090.0, 1160.0, 1400.0], &modes, 0.03);
    assert_eq!(a[0].dominant, "a");
    assert_eq!(a[1].dominant, "c");
    assert_eq!(a[2].dominant, "e");
    assert!(attribute(&[1.0], &[], 0.03).is_empty());
    assert!(attribution_text(&a[0]).starts_with("1090 Hz → coupled mode 1000 Hz"));
}

#[test]
fn bad_linearisation_is_an_error() {
    let track = sys(&[1.0], &[0.0]);
    let s = CoupledSystem {
        track: &track,
        wheel: &track,
        rail_rows: &[0.0; 3],
        wheel_rows: &[0.0; 3],
    };
    let mut lin = ContactLinearisation::uncoupled(10.0);
    lin.normal_stiffness_n_per_m = f64::NAN;
    assert!(coupled_state_modes(&s, &lin).is_err());
    let s2 = CoupledSystem {
        rail_rows: &[0.0; 2],
        ..s
    };
    assert!(coupled_state_modes(&s2, &ContactLinearisation::uncoupled(10.0)).is_err());
}
