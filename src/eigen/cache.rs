//! Modal cache (placeholder, filled below).
