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
//! The pipeline, one module per stage, data flowing one way (a stage never imports a later
//! one):
//!
//! | module | what it models |
//! |---|---|
//! | [`units`] | the one place where mm, µm and km/h are converted to SI |
//! | [`io`] | atomic output files: CSV, `.npy`, text |
//! | [`lists`] | list-valued inputs: a value given twice is refused |
//! | [`model`] | the TOML model file: parameters with units, `extends`, `--set` overrides, validation |
//! | [`mesh`] | UIC54 section, rail extrusion, sleepers, wheel of revolution |
//! | [`fe`] | hexahedral elements, spring-dampers, constraints, sparse K/M/C assembly |
//! | [`eigen`] | shift-invert Lanczos, Sturm check, mode classification, modal cache |
//! | [`contact`] | Hertz, half-space normal contact, Kalker transient tangential contact, frictional work |
//! | [`spectral`] | zero-phase band-pass, PSD in wavelength/frequency, peaks, deviations, phase |
//! | [`dynamics`] | the reduced-order wheel passage: modal synthesis, moving contact, time integration, wear |
//! | [`structure`] | the track and wheel substructures built from a model: supports, springs, holds |
//! | [`growth`] | trial corrugation, consistency table (Case 1/2, light/dark green, grey), growth phase |
//! | [`studies`] | speed sweeps (shards, resume, frequency-selection maps), initiation tables, design studies |
//! | [`report`] | SVG/PNG line plots and heat maps, Markdown/HTML documents |
//!
//! Coordinates (global, SI): `x` along the rail (direction of travel), `y` lateral (positive
//! away from the track centre, towards the field side), `z` vertical up. `z = 0` is the
//! underside of the rail foot at the rail centre line, `y = 0` is the rail centre line.
#![warn(missing_docs)]

pub mod contact;
pub mod dynamics;
pub mod eigen;
pub mod explicit;
pub mod fe;
pub mod growth;
pub mod io;
pub mod lists;
pub mod mesh;
pub mod model;
pub mod progress;
pub mod report;
pub mod spectral;
pub mod structure;
pub mod studies;
pub mod units;
