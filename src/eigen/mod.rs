//! Eigenmodes of the wheel–track substructures (K φ = ω² M φ).
