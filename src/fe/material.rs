//! Linear isotropic elastic materials.

use serde::{Deserialize, Serialize};

/// A linear isotropic elastic material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IsotropicElastic {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν (−), 0 ≤ ν < 0.5.
    pub poisson_ratio: f64,
    /// Mass density ρ (kg/m³).
    pub density: f64,
}

impl IsotropicElastic {
    /// Steel of rail and wheel (docs/theory.md §3.6): E = 210 GPa, ν = 0.3, ρ = 7800 kg/m³.
    pub const STEEL: IsotropicElastic = IsotropicElastic {
        youngs_modulus: 210.0e9,
        poisson_ratio: 0.3,
        density: 7800.0,
    };

    /// Shear modulus G = E / (2 (1 + ν)) (Pa).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Lamé's first parameter λ = E ν / ((1 + ν)(1 − 2ν)) (Pa).
    pub(crate) fn lame_lambda(&self) -> f64 {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    }

    /// Bar wave speed √(E/ρ) (m/s).
    pub fn bar_wave_speed(&self) -> f64 {
        (self.youngs_modulus / self.density).sqrt()
    }

    /// Isotropic elasticity matrix D (6 × 6, Pa) in Voigt order
    /// (εxx, εyy, εzz, γyz, γxz, γxy), engineering shear strains.
    pub fn elasticity_matrix(&self) -> nalgebra::SMatrix<f64, 6, 6> {
        let l = self.lame_lambda();
        let g = self.shear_modulus();
        let mut d = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                d[(i, j)] = l;
            }
            d[(i, i)] = l + 2.0 * g;
            d[(i + 3, i + 3)] = g;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::IsotropicElastic;
    #[test]
    fn steel_bar_wave_speed_is_5190() {
        // docs/theory.md §3.6: √(E/ρ) ≈ 5190 m/s.
        assert!((IsotropicElastic::STEEL.bar_wave_speed() - 5188.7).abs() < 1.0);
    }

    #[test]
    fn uniaxial_stress_from_d_matrix_gives_youngs_modulus() {
        // Inverting D for a uniaxial stress state must return σ/ε = E and −εyy/εxx = ν.
        let m = IsotropicElastic::STEEL;
        let c = m.elasticity_matrix().try_inverse().unwrap();
        let eps = c * nalgebra::SVector::<f64, 6>::from_column_slice(&[1.0, 0., 0., 0., 0., 0.]);
        assert!((1.0 / eps[0] - m.youngs_modulus).abs() / m.youngs_modulus < 1e-12);
        assert!((-eps[1] / eps[0] - m.poisson_ratio).abs() < 1e-12);
    }
}
