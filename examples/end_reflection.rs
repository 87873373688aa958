//! The energy reflection of the rail's ends over 0.3–3 kHz (validation/reference_regime.md,
//! part A): a straight unsupported UIC54 rail of the default model's section mesh (20 mm,
//! 10 mm at the running surface), node planes 40 mm apart, driven at one end face by a
//! longitudinal or a vertical traction; the far end free, with the face dashpots alone, or
//! absorbing (face dashpots and the default layer). Prints one row per frequency: the energy
//! reflection, the fitted wavenumber and the fit's residual for each case.
//!
//! Run: `cargo run --release --example end_reflection [-- layer_m rate_per_s]` (about a
//! minute on 2 cores).

use corrugation::fe::material::IsotropicElastic;
use corrugation::mesh::section::SectionParams;
use corrugation::model::{DEFAULT_ABSORBING_LAYER_M, DEFAULT_ABSORBING_LAYER_RATE};
use corrugation::structure::ends::reflection::{reflection, FarEnd, ReflectionRail, Wave};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let layer: f64 = args
        .get(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(DEFAULT_ABSORBING_LAYER_M);
    let rate: f64 = args
        .get(2)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(DEFAULT_ABSORBING_LAYER_RATE);
    let stretch = [2.5, 7.5];
    let rail = ReflectionRail {
        section: SectionParams {
            size_m: 0.02,
            running_surface_size_m: 0.01,
            ..SectionParams::default()
        },
        plane_spacing_m: 0.04,
        length_m: stretch[1] + 1.0 + layer,
        stretch_m: stretch,
        material: IsotropicElastic::STEEL,
    };
    println!(
        "rail {:.2} m, planes {} m apart, stretch {:?} m; layer {layer} m, α_max {rate} 1/s",
        rail.length_m, rail.plane_spacing_m, stretch
    );
    let ends = [
        ("free", FarEnd::Free),
        ("dashpots", FarEnd::Dashpots),
        (
            "absorbing",
            FarEnd::Absorbing {
                length: layer,
                rate,
            },
        ),
    ];
    for (wname, wave) in [
        ("longitudinal", Wave::Longitudinal),
        ("vertical bending", Wave::VerticalBending),
    ] {
        println!("\n{wname}: energy reflection (wavenumber rad/m; fit residual)");
        println!(
            "| f (Hz) | {} |",
            ends.iter().map(|e| e.0).collect::<Vec<_>>().join(" | ")
        );
        println!("|---|---|---|---|");
        for f in [300.0, 400.0, 500.0, 700.0, 1000.0, 1500.0, 2000.0, 3000.0] {
            let mut row = format!("| {f:.0} |");
            for (_, far) in ends {
                let r = reflection(&rail, far, wave, f)?;
                row += &format!(
                    " {:.2e} ({:.3}; {:.1e}) |",
                    r.energy, r.wavenumber_rad_per_m, r.residual
                );
            }
            println!("{row}");
        }
    }
    Ok(())
}
