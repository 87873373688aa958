//! # corrugation
//!
//! Predicts short-pitch rail corrugation (20–80 mm wear waves on the rail head) from first
//! principles: a 3D solid finite-element model of a ballasted track and a wheel, its
//! eigenmodes, a modal-superposition wheel passage coupled to transient frictional rolling
//! contact, and the wear-growth loop of Li et al. (TU Delft).
//!
//! The physics, equations and numerical methods of every stage, with the published
//! references, are in `docs/theory.md` of the repository (module docs cite its sections as
//! "docs/theory.md §N"); measured run times and the benchmark commands in
//! `docs/performance.md`.
//!
//! The pipeline, one module per concept, in layers (a module imports only its own layer or
//! lower ones; the table of modules, files and theory sections is `ARCHITECTURE.md` of the
//! repository):
//!
//! | layer | modules |
//! |---|---|
//! | 0, the foundation | [`units`] (mm, µm, km/h converted to SI in one place), [`huge_pages`] (the binary's allocator), [`io`], [`lists`], [`progress`], [`spectral`], [`report`], [`mesh`], [`fe`], [`contact`] |
//! | 1 | [`model`] (the TOML model file) → [`structure`] (track and wheel substructures) |
//! | 2 | [`eigen`] (Lanczos, Sturm check, classification, modal cache) |
//! | 3, the passage floor | [`passage`] (what a passage is, whichever engine runs it: runner traits, rail profile, records, contact line, set-up, statics) |
//! | 4, the two passage engines | [`dynamics`] (reduced modal passage), [`explicit`] (full explicit FE passage) |
//! | 5 | [`growth`] (trial corrugation, consistency, verdict), [`roughness`] (measured roughness, bands, forecast), [`studies`] (sweeps, studies, initiation, `roughness`, `predict`) |
//!
//! Coordinates (global, SI): `x` along the rail (direction of travel), `y` lateral (positive
//! away from the track centre, towards the field side), `z` vertical up. `z = 0` is the
//! underside of the rail foot at the rail centre line, `y = 0` is the rail centre line.
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

pub mod contact;
pub mod dynamics;
pub mod eigen;
pub mod explicit;
pub mod fe;
pub mod growth;
pub mod huge_pages;
pub mod io;
pub mod lists;
pub mod mesh;
pub mod model;
pub mod passage;
pub mod progress;
pub mod report;
pub mod roughness;
pub mod spectral;
pub mod structure;
pub mod studies;
pub mod units;
