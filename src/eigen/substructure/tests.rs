//! The substructured basis against the full track's Lanczos solution (independent solver on
//! the assembled K, M) on a short track.

use super::*;

/// A 4-bay track with a coarse mesh (the tests' small model).
fn small(extra: &[&str]) -> Model {
    crate::model::test_problems::small_model(extra).unwrap()
}

fn full_frequencies(track: &TrackStructure, fmax: f64) -> Vec<f64> {
    let (mats, _) = track.assemble().unwrap();
    solve(
        mats.k.as_ref(),
        mats.m.as_ref(),
        &EigenOptions::new(fmax),
        None,
    )
    .unwrap()
    .frequencies_hz
}

/// Largest relative frequency error below `below` Hz, with the Ritz bound checked (a
/// reduced eigenvalue is never below the exact one, up to 1e-5: the component modes and the
/// reference are Lanczos solutions with relative residuals near 1e-8, and a cluster of close
/// modes shares that error) and equal mode counts.
fn compare(sub: &[f64], full: &[f64], below: f64) -> f64 {
    let n = full.iter().filter(|&&f| f < below).count();
    assert!(
        sub.len() >= n,
        "{} substructured vs {n} full modes",
        sub.len()
    );
    let mut worst: f64 = 0.0;
    for i in 0..n {
        assert!(
            sub[i] >= full[i] * (1.0 - 1e-5),
            "mode {i}: {} Hz below the exact {} Hz (a Ritz value cannot be)",
            sub[i],
            full[i]
        );
        worst = worst.max((sub[i] - full[i]) / full[i]);
    }
    worst
}

/// Frequencies below 2 kHz within 0.5 % of the full Lanczos solution, for the components'
/// own railpad stiffness and for a 4× softer and a 2× stiffer pad reusing the same
/// components (the study's case: only the reduced eigenproblem is solved again).
#[test]
fn substructured_frequencies_match_the_full_solution_across_railpad_stiffness() {
    let fmax = 3000.0;
    let base = small(&[]);
    let track = TrackStructure::build(&base).unwrap();
    let t = std::time::Instant::now();
    let comp = build_components(&track, fmax, &SubstructureOptions::default()).unwrap();
    eprintln!(
        "components: rail {} ({} modes), sleeper {} ({} modes), reduced {} in {:.1} s",
        comp.rail.omega2.len(),
        comp.rail.modes,
        comp.sleeper.omega2.len(),
        comp.sleeper.modes,
        comp.reduced_size(),
        t.elapsed().as_secs_f64()
    );
    for k in [1.3e9, 0.325e9, 2.6e9] {
        let m = small(&[&format!("fastening.vertical_stiffness={k}")]);
        let tr = TrackStructure::build(&m).unwrap();
        let k_red = reduced_stiffness(&tr, &comp).unwrap();
        let (sub, _) = reduced_modes(&k_red, fmax).unwrap();
        let full = full_frequencies(&tr, fmax);
        let worst = compare(&sub, &full, 2000.0);
        eprintln!("k = {k:e}: worst relative error below 2 kHz {worst:e}");
        assert!(worst < 5e-3, "k = {k:e}: {worst}");
    }
}
