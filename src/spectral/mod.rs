//! Spectral analysis of signals along the rail.
