//! A small document writer: the same content as Markdown (`.md`) and as self-contained HTML
//! (`.html`, inline CSS, images by relative path). Used for `report.md` / `report.html` and the
//! tables of the sweeps and studies.
//!
//! Markdown tables escape `|`; HTML escapes `& < > "`. Images are referenced by a path
//! relative to the document (so the document and its plots can be moved together).

use std::path::{Path, PathBuf};

use super::ReportError;

/// One block of a document.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// A heading of level 1–6.
    Heading {
        /// Level (1 = title).
        level: u8,
        /// Text.
        text: String,
    },
    /// A paragraph of plain text.
    Paragraph(String),
    /// A table: header and rows of cells (rows shorter than the header are padded).
    Table {
        /// Column titles.
        header: Vec<String>,
        /// Rows of cells.
        rows: Vec<Vec<String>>,
        /// Background colour per cell in the HTML (CSS colour, e.g. `#c8f0c8`), by row and
        /// column; missing or `None` = none. Markdown has no cell colours: the cell's text
        /// must say what its colour shows.
        backgrounds: Vec<Vec<Option<&'static str>>>,
    },
    /// An image by relative path, with its alternative text (also the caption).
    Image {
        /// Alternative text / caption.
        alt: String,
        /// Path relative to the document.
        path: String,
    },
    /// Preformatted text (code, command lines).
    Code(String),
}

/// A document: a title and blocks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Document {
    /// Title (the `<title>` of the HTML and the level-1 heading).
    pub title: String,
    /// Content, in order.
    pub blocks: Vec<Block>,
}

/// The files written by [`Document::write`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DocFiles {
    /// `stem.md`.
    pub markdown: PathBuf,
    /// `stem.html`.
    pub html: PathBuf,
}

impl Document {
    /// An empty document with a title.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// Appends a heading (level clamped to 1–6).
    pub fn heading(&mut self, level: u8, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading {
            level: level.clamp(1, 6),
            text: text.into(),
        });
        self
    }

    /// Appends a paragraph.
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Appends a table.
    pub fn table<S: AsRef<str>>(&mut self, header: &[S], rows: Vec<Vec<String>>) -> &mut Self {
        self.table_shaded(header, rows, |_, _, _| None)
    }

    /// Appends a table whose HTML cells get the background `shade(row, column, text)` (a CSS
    /// colour) where it is `Some`.
    pub fn table_shaded<S: AsRef<str>>(
        &mut self,
        header: &[S],
        rows: Vec<Vec<String>>,
        shade: impl Fn(usize, usize, &str) -> Option<&'static str>,
    ) -> &mut Self {
        let backgrounds = rows
            .iter()
            .enumerate()
            .map(|(i, r)| r.iter().enumerate().map(|(j, c)| shade(i, j, c)).collect())
            .collect();
        self.blocks.push(Block::Table {
            header: header.iter().map(|h| h.as_ref().to_string()).collect(),
            rows,
            backgrounds,
        });
        self
    }

    /// Appends an image (path relative to the document).
    pub fn image(&mut self, alt: impl Into<String>, path: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Image {
            alt: alt.into(),
            path: path.into(),
        });
        self
    }

    /// Appends preformatted text.
    pub fn code(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Code(text.into()));
        self
    }

    /// The document as Markdown.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("# {}\n", self.title);
        for b in &self.blocks {
            out.push('\n');
            match b {
                Block::Heading { level, text } => {
                    out.push_str(&"#".repeat(*level as usize));
                    out.push(' ');
                    out.push_str(text);
                    out.push('\n');
                }
                Block::Paragraph(t) => {
                    out.push_str(t);
                    out.push('\n');
                }
                Block::Table { header, rows, .. } => {
                    let cell = |s: &str| s.replace('|', "\\|").replace('\n', " ");
                    let line = |cells: &mut dyn Iterator<Item = String>| {
                        let v: Vec<String> = cells.collect();
                        format!("| {} |\n", v.join(" | "))
                    };
                    out.push_str(&line(&mut header.iter().map(|h| cell(h))));
                    out.push_str(&line(&mut header.iter().map(|_| "---".to_string())));
                    for r in rows {
                        out.push_str(&line(
                            &mut (0..header.len().max(r.len()))
                                .map(|i| cell(r.get(i).map_or("", |s| s.as_str()))),
                        ));
                    }
                }
                Block::Image { alt, path } => {
                    out.push_str(&format!("![{}]({})\n", alt.replace(']', ")"), path));
                }
                Block::Code(t) => {
                    out.push_str("```\n");
                    out.push_str(t);
                    if !t.ends_with('\n') {
                        out.push('\n');
                    }
                    out.push_str("```\n");
                }
            }
        }
        out
    }

    /// The document as self-contained HTML (inline CSS; images by relative path).
    pub fn to_html(&self) -> String {
        let mut out =
            String::from("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        out.push_str(&format!("<title>{}</title>\n", escape(&self.title)));
        out.push_str(
            "<style>\nbody{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;line-height:1.45}\n\
             table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #bbb;padding:3px 8px;text-align:right}\n\
             th{background:#eee}img{max-width:100%}figure{margin:1em 0}figcaption{color:#555;font-size:90%}\n\
             pre{background:#f4f4f4;padding:.6em;overflow-x:auto}\n</style>\n</head>\n<body>\n",
        );
        out.push_str(&format!("<h1>{}</h1>\n", escape(&self.title)));
        for b in &self.blocks {
            match b {
                Block::Heading { level, text } => {
                    out.push_str(&format!("<h{level}>{}</h{level}>\n", escape(text)));
                }
                Block::Paragraph(t) => out.push_str(&format!("<p>{}</p>\n", escape(t))),
                Block::Table {
                    header,
                    rows,
                    backgrounds,
                } => {
                    out.push_str("<table>\n<tr>");
                    for h in header {
                        out.push_str(&format!("<th>{}</th>", escape(h)));
                    }
                    out.push_str("</tr>\n");
                    for (k, r) in rows.iter().enumerate() {
                        out.push_str("<tr>");
                        for i in 0..header.len().max(r.len()) {
                            let c = r.get(i).map_or("", |s| s.as_str());
                            match backgrounds.get(k).and_then(|b| b.get(i)).copied().flatten() {
                                Some(bg) => out.push_str(&format!(
                                    "<td style=\"background:{}\">{}</td>",
                                    escape(bg),
                                    escape(c)
                                )),
                                None => out.push_str(&format!("<td>{}</td>", escape(c))),
                            }
                        }
                        out.push_str("</tr>\n");
                    }
                    out.push_str("</table>\n");
                }
                Block::Image { alt, path } => out.push_str(&format!(
                    "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                    escape(path),
                    escape(alt),
                    escape(alt)
                )),
                Block::Code(t) => out.push_str(&format!("<pre>{}</pre>\n", escape(t))),
            }
        }
        out.push_str("</body>\n</html>\n");
        out
    }

    /// Writes `stem.md` and `stem.html` atomically.
    pub fn write(&self, stem: &Path) -> Result<DocFiles, ReportError> {
        let with = |ext: &str| {
            let mut n = stem.file_name().unwrap_or_default().to_os_string();
            n.push(ext);
            stem.with_file_name(n)
        };
        let (md, html) = (with(".md"), with(".html"));
        for (path, text) in [(&md, self.to_markdown()), (&html, self.to_html())] {
            crate::io::write_text(path, &text).map_err(|source| ReportError::Io {
                path: path.clone(),
                source,
            })?;
        }
        Ok(DocFiles { markdown: md, html })
    }
}

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c => o.push(c),
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Document {
        let mut d = Document::new("Report <1>");
        d.heading(2, "Table")
            .paragraph("a & b")
            .table(
                &["name", "λ (mm)"],
                vec![vec!["x|y".into(), "42".into()], vec!["z".into()]],
            )
            .image("Map", "plots/map.png")
            .code("corrugation sweep");
        d
    }

    #[test]
    fn markdown_has_headings_table_image() {
        let md = sample().to_markdown();
        assert_eq!(
            md,
            "# Report <1>\n\n## Table\n\na & b\n\n| name | λ (mm) |\n| --- | --- |\n| x\\|y | 42 |\n| z |  |\n\n![Map](plots/map.png)\n\n```\ncorrugation sweep\n```\n"
        );
    }

    #[test]
    fn html_is_escaped_and_self_contained() {
        let h = sample().to_html();
        assert!(h.contains("<title>Report &lt;1&gt;</title>"));
        assert!(h.contains("<p>a &amp; b</p>"));
        assert!(h.contains("<td>x|y</td><td>42</td>"));
        assert!(h.contains("<td>z</td><td></td>"));
        assert!(h.contains("<img src=\"plots/map.png\""));
        assert!(h.contains("<style>") && !h.contains("<link") && !h.contains("<script"));
    }

    /// A shaded cell carries its background in the HTML only; the Markdown keeps its text.
    #[test]
    fn shaded_cells_are_coloured_in_html_only() {
        let mut d = Document::new("t");
        d.table_shaded(
            &["amplitude", "class"],
            vec![
                vec!["10".into(), "light green".into()],
                vec!["40".into(), "grey".into()],
            ],
            |_, j, c| (j == 1 && c == "light green").then_some("#c8f0c8"),
        );
        let h = d.to_html();
        assert!(h.contains("<td>10</td><td style=\"background:#c8f0c8\">light green</td>"));
        assert!(h.contains("<td>40</td><td>grey</td>"));
        assert!(d.to_markdown().contains("| 10 | light green |"));
    }

    #[test]
    fn write_creates_both_files() {
        let d = std::env::temp_dir().join(format!("corrugation-doc-{}", std::process::id()));
        let f = sample().write(&d.join("report")).unwrap();
        assert!(std::fs::read_to_string(&f.markdown)
            .unwrap()
            .starts_with("# Report"));
        assert!(std::fs::read_to_string(&f.html)
            .unwrap()
            .starts_with("<!DOCTYPE html>"));
        std::fs::remove_dir_all(d).ok();
    }
}
