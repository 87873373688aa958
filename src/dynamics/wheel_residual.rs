//! Residual (static) flexibility of the wheel at the contact (docs/theory.md §7.7).
//!
//! # What it is
//! The wheel's modes below f_max miss the quasi-static response of its higher modes, as the
//! track's do ([`super::residual`]). The wheel floats: its modal basis (and the passage) has
//! three rigid-body modes (x, z with the sprung mass, rotation about the axle), so `K` is
//! singular and its static flexibility is the **elastic** one of the free body, by inertia
//! relief (Craig & Kurdila 2006; Géradin & Rixen 2015):
//!
//! ```text
//! P   = I − M Φ_r Φ_rᵀ                       removes the rigid part of a load (Φ_rᵀ M Φ_r = I)
//! G_e = Pᵀ K_c⁻¹ P = Σ_{elastic i} φ_i φ_iᵀ / ω_i²    elastic flexibility (m/N)
//! G_d = b_dᵀ G_e b_d,   M_d = Σ_{kept elastic} r_{d,i}² / ω_i²,   R_d = G_d − M_d ≥ 0
//! ```
//!
//! `K_c` is `K` held at as many DOFs as there are rigid modes, chosen so that they fix the
//! rigid motion in a statically determinate way; a balanced load `P b` has no reactions there,
//! so the holding springs' size does not matter and `K_c⁻¹ P b` differs from the free body's
//! elastic deflection by a rigid motion only, which `Pᵀ` removes. The same constraints as the
//! modes (the symmetry plane held laterally, the sprung mass on the primary suspension).
//!
//! # Which load
//! The contact load of the passage sits on the tread ring at θ = 0 with the lateral weights
//! of [`super::reduced::WheelContact`]. As for the rail, the flexibility of a load on one
//! node ring contains the mesh's local indentation under it, which the contact's half-space
//! already supplies (docs/theory.md §7.7, "do not count local flexibility twice"); the
//! passage uses the **structural** residual: the load shared equally by the contact ring and
//! a neighbour ring (θ = ±Δθ), the mean of the two, `¼(R_00 + R_jj + 2R_0j)`.

use faer::sparse::SparseColMatRef;
use faer::Mat;
use serde::{Deserialize, Serialize};

use super::reduced::{add_nodes_load, ContactFrame, WheelContact};
use super::DynamicsError;
pub use crate::passage::free_body::{elastic_flexibility, FreeBody};
use crate::structure::WheelStructure;

/// The wheel's flexibility at the contact in the contact frame `[x, t, n]` (m/N).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WheelResidual {
    /// Elastic static flexibility `b_dᵀ G_e b_d` of the contact ring's load (m/N).
    pub static_m_per_n: [f64; 3],
    /// Modal part of the kept elastic modes, `Σ r_d² / ω²` (m/N).
    pub modal_m_per_n: [f64; 3],
    /// Residual of the contact ring's load, `G − modal` (m/N): contains local indentation.
    pub point_residual_m_per_n: [f64; 3],
    /// Structural residual (m/N): the load shared by the contact ring and a neighbour ring,
    /// mean over the two neighbours; the series compliance the passage applies.
    pub structural_m_per_n: [f64; 3],
    /// Kept modes (−), of which rigid (−).
    pub modes: usize,
    /// Rigid-body modes among them (−).
    pub rigid_modes: usize,
}

/// What the wheel's residual flexibility is computed from.
#[derive(Clone, Copy)]
pub struct WheelModes<'a> {
    /// The wheel substructure.
    pub wheel: &'a WheelStructure,
    /// Stiffness over the free DOFs (N/m, full symmetric storage).
    pub k: SparseColMatRef<'a, usize, f64>,
    /// Mass over the free DOFs (kg, full symmetric storage).
    pub m: SparseColMatRef<'a, usize, f64>,
    /// Kept mass-normalised modes (free DOFs × modes).
    pub modes: &'a Mat<f64>,
    /// Their ω² (rad²/s²); exactly 0 for the rigid-body modes.
    pub omega2: &'a [f64],
    /// The contact frame.
    pub frame: &'a ContactFrame,
    /// Hertz semi-axis across the rail (m): the lateral spread of the load.
    pub half_width_m: f64,
}

/// The nodes and lateral weights of the tread ring at angle index `k`, as the passage's
/// contact load ([`WheelContact::ring_nodes`]).
fn ring(wm: &WheelModes<'_>, k: usize) -> Vec<(usize, f64)> {
    WheelContact::ring_nodes(wm.wheel, k, wm.half_width_m)
}

impl WheelResidual {
    /// Computes the wheel's elastic static flexibility at the contact by one sparse LDLᵀ of
    /// the held stiffness, and its residual over the kept modes `wm`.
    pub fn compute(wm: WheelModes<'_>) -> Result<Self, DynamicsError> {
        let n = wm.modes.nrows();
        let nm = wm.modes.ncols();
        if wm.omega2.len() != nm || wm.k.nrows() != n || wm.m.nrows() != n {
            return Err(DynamicsError::SizeMismatch {
                what: "wheel residual flexibility: modes, frequencies and matrices (build them from the same wheel)",
                found: wm.omega2.len(),
                expected: nm,
            });
        }
        // The wheel body's DOFs hold the rigid motion, not the sprung mass (it hangs on the
        // soft primary suspension).
        let dm = &wm.wheel.dofmap;
        let sprung: Vec<usize> = (0..3)
            .filter_map(|c| dm.free_index(3 * wm.wheel.sprung_node + c))
            .collect();
        let topo = &wm.wheel.topology;
        let nk = topo.thetas.len();
        let k0 = topo.contact_angle_index();
        let rings = [k0, (k0 + nk - 1) % nk, (k0 + 1) % nk].map(|k| ring(&wm, k));
        // Loads of the three rings × three directions.
        let mut loads = Vec::with_capacity(9);
        for nodes in &rings {
            for d in 0..3 {
                let mut force = [0.0; 3];
                force[d] = 1.0;
                let mut b = vec![0.0; n];
                add_nodes_load(nodes, dm, wm.frame, 1.0, force, &mut b);
                loads.push(b);
            }
        }
        let gm = elastic_flexibility(
            FreeBody {
                k: wm.k,
                m: wm.m,
                modes: wm.modes,
                omega2: wm.omega2,
                exclude: &sprung,
            },
            &loads,
        )?;
        let g = |a: usize, b: usize, d: usize| gm[3 * a + d][3 * b + d];
        let rigid_modes = wm.omega2.iter().filter(|&&w| w == 0.0).count();
        // Modal rows of the rings and the kept elastic modes' part.
        let rows: Vec<Vec<f64>> = rings
            .iter()
            .map(|nodes| {
                let mut r = vec![0.0; 3 * nm];
                super::reduced::modal_rows(nodes, &wm.wheel.dofmap, wm.modes, wm.frame, &mut r);
                r
            })
            .collect();
        let modal = |a: usize, b: usize, d: usize| -> f64 {
            (0..nm)
                .filter(|&i| wm.omega2[i] > 0.0)
                .map(|i| rows[a][d * nm + i] * rows[b][d * nm + i] / wm.omega2[i])
                .sum()
        };
        let res = |a: usize, b: usize, d: usize| g(a, b, d) - modal(a, b, d);
        let mut out = WheelResidual {
            static_m_per_n: [0.0; 3],
            modal_m_per_n: [0.0; 3],
            point_residual_m_per_n: [0.0; 3],
            structural_m_per_n: [0.0; 3],
            modes: nm,
            rigid_modes,
        };
        for d in 0..3 {
            out.static_m_per_n[d] = g(0, 0, d);
            out.modal_m_per_n[d] = modal(0, 0, d);
            out.point_residual_m_per_n[d] = res(0, 0, d);
            let mid = |j: usize| 0.25 * (res(0, 0, d) + res(j, j, d) + 2.0 * res(0, j, d));
            out.structural_m_per_n[d] = 0.5 * (mid(1) + mid(2));
            let gd = out.static_m_per_n[d];
            if !(gd.is_finite() && gd > 0.0) || out.point_residual_m_per_n[d] < -1e-6 * gd {
                return Err(DynamicsError::WheelResidualBelowModal {
                    direction: d,
                    fe_m_per_n: gd,
                    modal_m_per_n: out.modal_m_per_n[d],
                });
            }
            out.point_residual_m_per_n[d] = out.point_residual_m_per_n[d].max(0.0);
            out.structural_m_per_n[d] = out.structural_m_per_n[d].max(0.0);
        }
        Ok(out)
    }
}

/// Revision of [`WheelResidual::cached`]'s file (its name and layout) and of the
/// computation: bump it when either changes, so that no stale file is read.
pub(crate) const WHEEL_RESIDUAL_REVISION: u64 = 1;

impl WheelResidual {
    /// The value's exact bytes: the twelve flexibilities' bit patterns, then the mode and
    /// rigid-mode counts, each as 8 little-endian bytes.
    fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(14 * 8);
        for v in [
            &self.static_m_per_n,
            &self.modal_m_per_n,
            &self.point_residual_m_per_n,
            &self.structural_m_per_n,
        ] {
            v.iter().for_each(|x| b.extend(x.to_le_bytes()));
        }
        b.extend((self.modes as u64).to_le_bytes());
        b.extend((self.rigid_modes as u64).to_le_bytes());
        b
    }

    /// The value of [`Self::to_bytes`]'s bytes; `None` when they are not 14 words.
    fn from_bytes(b: &[u8]) -> Option<Self> {
        if b.len() != 14 * 8 {
            return None;
        }
        let word = |i: usize| -> [u8; 8] { b[8 * i..8 * i + 8].try_into().expect("8 bytes") };
        let v3 = |k: usize| std::array::from_fn(|d| f64::from_le_bytes(word(3 * k + d)));
        Some(WheelResidual {
            static_m_per_n: v3(0),
            modal_m_per_n: v3(1),
            point_residual_m_per_n: v3(2),
            structural_m_per_n: v3(3),
            modes: usize::try_from(u64::from_le_bytes(word(12))).ok()?,
            rigid_modes: usize::try_from(u64::from_le_bytes(word(13))).ok()?,
        })
    }

    /// True when this value can belong to `wm`: its mode counts are `wm`'s and its
    /// flexibilities are finite, the static ones positive and the residuals ≥ 0.
    fn fits(&self, wm: &WheelModes<'_>) -> bool {
        let rigid = wm.omega2.iter().filter(|&&w| w == 0.0).count();
        let all = [
            self.static_m_per_n,
            self.modal_m_per_n,
            self.point_residual_m_per_n,
            self.structural_m_per_n,
        ];
        self.modes == wm.modes.ncols()
            && self.rigid_modes == rigid
            && all.iter().flatten().all(|x| x.is_finite())
            && self.static_m_per_n.iter().all(|&x| x > 0.0)
            && self.point_residual_m_per_n.iter().all(|&x| x >= 0.0)
            && self.structural_m_per_n.iter().all(|&x| x >= 0.0)
    }

    /// The name of the cache file of `wm`'s value: the revision and a digest of what
    /// determines the value besides the wheel's matrices and modes (which the cache entry's
    /// key covers): the modes' ω², the contact frame and the load's half-width.
    fn cache_name(wm: &WheelModes<'_>) -> String {
        let mut h = blake3::Hasher::new();
        h.update(&(wm.modes.nrows() as u64).to_le_bytes());
        let f = wm.frame;
        let words = wm.omega2.iter().chain([&wm.half_width_m]).chain(f.x.iter());
        for x in words.chain(f.t.iter()).chain(f.n.iter()) {
            h.update(&x.to_bits().to_le_bytes());
        }
        let hex = h.finalize().to_hex();
        format!(
            "wheel-residual-r{WHEEL_RESIDUAL_REVISION}-{}.bin",
            &hex[..32]
        )
    }

    /// The residual flexibility of `wm` from the auxiliary file of the wheel basis's cache
    /// entry `key`, or computed ([`Self::compute`]) and stored there (a failure to store is
    /// reported to the cache's progress, not an error). The file holds the values' bit
    /// patterns, so a cached value is the computed one exactly. The flag is true for a value
    /// read from the cache.
    pub fn cached(
        cache: &crate::eigen::cache::ModalCache,
        key: &crate::eigen::cache::CacheKey,
        wm: WheelModes<'_>,
    ) -> Result<(Self, bool), DynamicsError> {
        let name = Self::cache_name(&wm);
        if let Some(r) = cache
            .load_aux(key, &name)
            .and_then(|b| Self::from_bytes(&b))
        {
            if r.fits(&wm) {
                return Ok((r, true));
            }
        }
        let r = Self::compute(wm)?;
        if let Err(e) = cache.store_aux(key, &name, &r.to_bytes()) {
            cache.progress().warn(&format!(
                "could not cache the wheel's residual flexibility: {e}"
            ));
        }
        Ok((r, false))
    }
}

#[cfg(test)]
mod tests {
    use super::{elastic_flexibility, FreeBody, Mat, WheelResidual};
    use faer::sparse::{SparseColMat, Triplet};

    /// A free body with a known spectrum: `K = M Φ Λ Φᵀ M` with `Φ = M^{-½} Q` (Q orthogonal,
    /// so `ΦᵀMΦ = I`) and three zero eigenvalues. The elastic flexibility between two loads is
    /// then the closed form `Σ_{λ>0} (φᵀb_a)(φᵀb_b)/λ`; inertia relief must give it from the
    /// truncated basis' rigid modes alone, and with every mode kept the residual vanishes.
    /// The cache file's bytes give back the value bit for bit; a payload of another length
    /// is refused.
    #[test]
    fn cached_bytes_round_trip_exactly() {
        let r = WheelResidual {
            static_m_per_n: [1.0 / 3.0, 2.5e-10, f64::MIN_POSITIVE],
            modal_m_per_n: [0.1, 0.2, 0.30000000000000004],
            point_residual_m_per_n: [7e-11, 0.0, 1e-300],
            structural_m_per_n: [std::f64::consts::PI * 1e-11, 5e-12, 6e-12],
            modes: 96,
            rigid_modes: 3,
        };
        let b = r.to_bytes();
        assert_eq!(WheelResidual::from_bytes(&b), Some(r));
        assert_eq!(WheelResidual::from_bytes(&b[..b.len() - 1]), None);
    }

    #[test]
    fn inertia_relief_gives_the_closed_form_elastic_flexibility() {
        let n = 24;
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64).collect();
        let a = nalgebra::DMatrix::<f64>::from_fn(n, n, |i, j| {
            (((i * 31 + j * 17) % 13) as f64 - 6.0) / 7.0 + if i == j { 3.0 } else { 0.0 }
        });
        let q = a.qr().q();
        let phi = nalgebra::DMatrix::<f64>::from_fn(n, n, |i, j| q[(i, j)] / mass[i].sqrt());
        let lam: Vec<f64> = (0..n)
            .map(|j| if j < 3 { 0.0 } else { 1e4 * (j as f64).powi(2) })
            .collect();
        let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
        for j in 0..n {
            let mp: Vec<f64> = (0..n).map(|i| mass[i] * phi[(i, j)]).collect();
            for r in 0..n {
                for c in 0..n {
                    k[(r, c)] += lam[j] * mp[r] * mp[c];
                }
            }
        }
        let trip_k: Vec<Triplet<usize, usize, f64>> = (0..n)
            .flat_map(|c| (0..n).map(move |r| (r, c)))
            .map(|(r, c)| Triplet::new(r, c, 0.5 * (k[(r, c)] + k[(c, r)])))
            .collect();
        let trip_m: Vec<Triplet<usize, usize, f64>> = (0..n)
            .flat_map(|c| (0..n).map(move |r| (r, c)))
            .map(|(r, c)| Triplet::new(r, c, if r == c { mass[r] } else { 0.0 }))
            .collect();
        let ks = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip_k).unwrap();
        let ms = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip_m).unwrap();
        let loads: Vec<Vec<f64>> = (0..2)
            .map(|l| (0..n).map(|i| ((i * (l + 3)) % 7) as f64 - 2.5).collect())
            .collect();
        let proj = |j: usize, b: &[f64]| (0..n).map(|i| phi[(i, j)] * b[i]).sum::<f64>();
        let closed = |a: usize, b: usize, from: usize| -> f64 {
            (from.max(3)..n)
                .map(|j| proj(j, &loads[a]) * proj(j, &loads[b]) / lam[j])
                .sum()
        };
        for kept in [3, 10, n] {
            let modes = Mat::<f64>::from_fn(n, kept, |i, j| phi[(i, j)]);
            let g = elastic_flexibility(
                FreeBody {
                    k: ks.as_ref(),
                    m: ms.as_ref(),
                    modes: &modes,
                    omega2: &lam[..kept],
                    exclude: &[],
                },
                &loads,
            )
            .unwrap();
            for a in 0..2 {
                for b in 0..2 {
                    let want = closed(a, b, 0);
                    assert!(
                        (g[a][b] - want).abs() < 1e-9 * closed(a, a, 0),
                        "{kept} modes, G[{a}][{b}] {} vs {want}",
                        g[a][b]
                    );
                    // residual = G − kept modes' part = the truncated modes' part
                    let modal: f64 = (3..kept)
                        .map(|j| proj(j, &loads[a]) * proj(j, &loads[b]) / lam[j])
                        .sum();
                    let resid = closed(a, b, kept);
                    assert!((g[a][b] - modal - resid).abs() < 1e-9 * closed(a, a, 0));
                    if kept == n {
                        assert!((g[a][b] - modal).abs() < 1e-9 * closed(a, a, 0));
                    }
                }
            }
        }
    }
}
