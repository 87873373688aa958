//! The modal-cache entries of the component bases: their key (the track's structural key
//! without the spring stiffnesses) and their storage.

use super::{
    BasisError, CacheKey, CacheLookup, CacheMeta, ComponentBasis, ModalCache, Model,
    SubstructureOptions,
};

/// Revision of the component construction (bump when the bases of an unchanged model change).
pub(crate) const COMPONENT_REVISION: u64 = 2;

/// The cache key of a track's component `part` (`rail-component` or `sleeper-component`):
/// the track's identity without any spring stiffness ([`crate::model::identity::IdentityScope::Components`]), but
/// with the railpad directions that have springs at all (a direction with zero stiffness and
/// zero damping has none, which changes the spring layout), f_max and the options. Hold and
/// ballast springs exist whatever their stiffness.
pub fn component_key(
    m: &Model,
    fmax_hz: f64,
    opts: &SubstructureOptions,
    part: &str,
) -> Result<CacheKey, BasisError> {
    let bytes = crate::model::identity::model_identity(
        m,
        crate::model::identity::IdentityScope::Components,
    )
    .map_err(BasisError::Json)?;
    let (k, c) = (
        m.fastening.springs.stiffness(),
        m.fastening.springs.damping(),
    );
    let active: u64 = (0..3)
        .filter(|&d| k[d] != 0.0 || c[d] != 0.0)
        .map(|d| 1u64 << d)
        .sum();
    let key = CacheKey::new()
        .u64("physics_revision", crate::eigen::basis::PHYSICS_REVISION)
        .u64("component_revision", COMPONENT_REVISION)
        .bytes("model", &bytes)
        .u64("railpad_directions", active)
        .f64("f_max_hz", fmax_hz)
        .f64("cutoff_factor", opts.cutoff_factor)
        .f64("sleeper_cutoff_factor", opts.sleeper_cutoff_factor)
        .u64("pattern_degree", opts.pattern_degree as u64)
        .u64("ballast_pattern_degree", opts.ballast_pattern_degree as u64)
        .str("substructure", part);
    crate::eigen::basis::section_mesh_keyed(key, m)
}

pub(super) fn store_component(cache: &ModalCache, key: &CacheKey, c: &ComponentBasis, fmax: f64) {
    let freqs: Vec<f64> = c
        .omega2
        .iter()
        .map(|&w| w.sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let meta = CacheMeta {
        key: String::new(),
        crate_version: String::new(),
        n_dofs: c.vectors.nrows(),
        n_modes: c.vectors.ncols(),
        f_min_hz: 0.0,
        f_max_hz: fmax,
        sturm_count: c.modes,
        relative_residuals: vec![],
        m_orthonormality_error: 0.0,
        frequencies_blake3: String::new(),
        modes_blake3: String::new(),
        classification: serde_json::json!({ "component_modes": c.modes, "omega2": c.omega2 }),
    };
    if let Err(e) = cache.store(key, &freqs, &c.vectors, meta) {
        cache.progress().warn(&format!(
            "could not store a track component basis in the cache: {e}"
        ));
    }
}

pub(super) fn load_component(
    cache: &ModalCache,
    key: &CacheKey,
    n: usize,
) -> Option<ComponentBasis> {
    let CacheLookup::Hit(c) = cache.load(key) else {
        return None;
    };
    let modes = c.meta.classification.get("component_modes")?.as_u64()? as usize;
    let omega2: Vec<f64> =
        serde_json::from_value(c.meta.classification.get("omega2")?.clone()).ok()?;
    (c.modes.nrows() == n && omega2.len() == c.modes.ncols() && modes <= omega2.len()).then_some(
        ComponentBasis {
            vectors: c.modes,
            omega2,
            modes,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::{load_component, store_component, CacheKey, ComponentBasis, ModalCache};
    use faer::Mat;

    /// A component basis read back from the cache is the stored one bit for bit, its `ω̃²`
    /// included (they travel as JSON text): a study's first run, which uses the bases it
    /// has just computed, and its rerun from the cache then give the same results. Ten
    /// thousand values spread over the components' range of `ω̃²` (rad²/s²), where a
    /// parser that is not correctly rounded is off by one unit in the last place for some.
    #[test]
    fn a_cached_component_basis_reads_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let cache = ModalCache::new(dir.path());
        let key = CacheKey::new().str("substructure", "roundtrip");
        let n = 10_000;
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        let omega2: Vec<f64> = (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let u = (x >> 11) as f64 / (1u64 << 53) as f64;
                10f64.powf(2.0 + 8.0 * u) * (1.0 + u)
            })
            .collect();
        let basis = ComponentBasis {
            vectors: Mat::from_fn(3, n, |i, j| (i + 1) as f64 / (j + 1) as f64),
            omega2,
            modes: n / 2,
        };
        store_component(&cache, &key, &basis, 5000.0);
        let back = load_component(&cache, &key, 3).expect("the stored basis");
        assert_eq!(back.modes, basis.modes);
        let differ = (basis.omega2.iter().zip(&back.omega2))
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        assert_eq!(
            differ, 0,
            "{differ} of {n} values changed on the way through the cache"
        );
        assert!((0..n).all(|j| (0..3).all(|i| back.vectors[(i, j)] == basis.vectors[(i, j)])));
    }
}
