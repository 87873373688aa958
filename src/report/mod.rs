//! Plots and documents of the reports: every command writes its figures and its summary
//! through this module, so that all outputs look alike.
//!
//! - [`plot`]: line plots (linear or logarithmic y) and heat maps (linear or logarithmic
//!   colour scale, with overlay lines), each written as `stem.svg` **and** `stem.png`.
//! - [`doc`]: a small Markdown + HTML document writer (headings, paragraphs, tables, images
//!   by relative path); the HTML is self-contained apart from the images.
//!
//! PNG text is rendered with DejaVu Sans, embedded in the binary (`src/report/fonts`, Bitstream
//! Vera licence, see `LICENSE-DejaVu.txt` there), so the plots need no system font or font
//! library: a fresh CI machine renders them identically. SVG files name the `sans-serif`
//! family and let the viewer choose the font.
//!
//! All files are written atomically (temp file + rename, as [`crate::io`]): an interrupted run
//! never leaves a plot that looks complete but is not.

pub mod doc;
pub mod plot;

use std::path::PathBuf;

/// Errors of the report writers. Each names the file and what to change.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The plotting library failed to draw.
    #[error("{path}: cannot draw the plot: {message}")]
    Draw {
        /// The file.
        path: PathBuf,
        /// The plotting library's message.
        message: String,
    },
    /// The data cannot be plotted (lengths differ, no finite value, ...).
    #[error("plot `{title}`: {reason}")]
    Data {
        /// The plot title.
        title: String,
        /// What is wrong and what to change.
        reason: String,
    },
}
