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
    pub(crate) fn to_markdown(&self) -> String {
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
    pub(crate) fn to_html(&self) -> String {
        let mut out =
            String::from("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        out.push_str(&format!("<title>{}</title>\n", escape(&self.title)));
        out.push_str(
            "<style>\nbody{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;line-height:1.45}\n\
             table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #bbb;padding:3px 8px;text-align:left}\n\
             th.n,td.n{text-align:right}\n\
             th{background:#eee}img{max-width:100%}figure{margin:1em 0}figcaption{color:#555;font-size:90%}\n\
             pre{background:#f4f4f4;padding:.6em;overflow-x:auto}\n</style>\n</head>\n<body>\n",
        );
        out.push_str(&format!("<h1>{}</h1>\n", escape(&self.title)));
        for b in &self.blocks {
            match b {
                Block::Heading { level, text } => {
                    out.push_str(&format!("<h{level}>{}</h{level}>\n", escape(text)));
                }
                Block::Paragraph(t) => out.push_str(&format!("<p>{}</p>\n", inline_html(t))),
                Block::Table {
                    header,
                    rows,
                    backgrounds,
                } => {
                    let width = rows.iter().map(Vec::len).fold(header.len(), usize::max);
                    // A column of numbers is right-aligned, any other left-aligned.
                    let class: Vec<&str> = (0..width)
                        .map(|i| {
                            let mut cells = rows.iter().filter_map(|r| r.get(i)).peekable();
                            let numbers = cells.peek().is_some()
                                && cells.all(|c| is_placeholder(c) || is_number(c));
                            if numbers {
                                " class=\"n\""
                            } else {
                                ""
                            }
                        })
                        .collect();
                    out.push_str("<table>\n<tr>");
                    for (i, h) in header.iter().enumerate() {
                        out.push_str(&format!("<th{}>{}</th>", class[i], escape(h)));
                    }
                    out.push_str("</tr>\n");
                    for (k, r) in rows.iter().enumerate() {
                        out.push_str("<tr>");
                        for (i, cls) in class.iter().enumerate().take(header.len().max(r.len())) {
                            let c = r.get(i).map_or("", |s| s.as_str());
                            match backgrounds.get(k).and_then(|b| b.get(i)).copied().flatten() {
                                Some(bg) => out.push_str(&format!(
                                    "<td{cls} style=\"background:{}\">{}</td>",
                                    escape(bg),
                                    escape(c)
                                )),
                                None => out.push_str(&format!("<td{cls}>{}</td>", escape(c))),
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

/// Summary lines (as a command prints them, one per line, lower-case starts allowed) as one
/// paragraph of sentences: each line's first letter in upper case, joined by `". "`, ended
/// by a full stop.
pub fn sentences(lines: &[String]) -> String {
    let mut out = String::new();
    for (i, l) in lines.iter().enumerate() {
        if i > 0 {
            out.push_str(". ");
        }
        let mut c = l.chars();
        if let Some(first) = c.next() {
            out.extend(first.to_uppercase());
            out.push_str(c.as_str());
        }
    }
    if !out.is_empty() && !out.ends_with('.') {
        out.push('.');
    }
    out
}

/// Whether a table cell holds no value: empty, or a dash standing for none (`–`, `—`, `-`).
fn is_placeholder(cell: &str) -> bool {
    matches!(cell.trim(), "" | "–" | "—" | "-")
}

/// Whether a table cell reads as one number: a decimal or exponent number, optionally signed,
/// optionally followed by a percent sign (`42`, `+0.47`, `1.0e-5`, `0.110 %`).
fn is_number(cell: &str) -> bool {
    let t = cell.trim();
    let t = t.strip_suffix('%').map_or(t, str::trim_end);
    !t.is_empty() && t.parse::<f64>().is_ok_and(f64::is_finite)
}

/// A paragraph's text for HTML: escaped, and `**…**` pairs (the Markdown's bold) as
/// `<strong>…</strong>`; an unpaired `**` stays as written.
fn inline_html(text: &str) -> String {
    let parts: Vec<&str> = text.split("**").collect();
    if parts.len().is_multiple_of(2) {
        return escape(text);
    }
    parts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            if i % 2 == 1 {
                format!("<strong>{}</strong>", escape(p))
            } else {
                escape(p)
            }
        })
        .collect()
}

/// Escapes text for HTML.
pub(crate) fn escape(s: &str) -> String {
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
    use super::{is_number, sentences, Document};
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
        assert!(h.contains("<td>x|y</td><td class=\"n\">42</td>"));
        assert!(h.contains("<td>z</td><td class=\"n\"></td>"));
        assert!(h.contains("<img src=\"plots/map.png\""));
        assert!(h.contains("<style>") && !h.contains("<link") && !h.contains("<script"));
    }

    /// Columns of numbers are right-aligned, text columns left-aligned; `**bold**` in a
    /// paragraph is bold in the HTML, an unpaired `**` is kept.
    #[test]
    fn numbers_right_text_left_and_bold() {
        assert!(is_number("42") && is_number("+0.47") && is_number("1.0e-5"));
        assert!(is_number("0.110 %") && is_number("-3%"));
        assert!(!is_number("36.5 mm / 1065 Hz") && !is_number("no") && !is_number("%"));
        assert!(!is_number("nan") && !is_number(""));
        let mut d = Document::new("t");
        d.paragraph("**Summary.** 2 < 3").paragraph("a ** b").table(
            &["case", "name", "r"],
            vec![
                vec!["0".into(), "k=1".into(), "0.5 %".into()],
                vec!["1".into(), "k=2".into(), "".into()],
                vec!["2".into(), "k=3".into(), "–".into()],
            ],
        );
        let h = d.to_html();
        assert!(h.contains("<p><strong>Summary.</strong> 2 &lt; 3</p>"));
        assert!(h.contains("<p>a ** b</p>"));
        assert!(h.contains("<th class=\"n\">case</th><th>name</th><th class=\"n\">r</th>"));
        assert!(h.contains("<td class=\"n\">1</td><td>k=2</td><td class=\"n\"></td>"));
    }

    #[test]
    fn summary_lines_become_sentences() {
        let l = vec!["2 case(s)".to_string(), "lowest F_L 8.5 N".into()];
        assert_eq!(sentences(&l), "2 case(s). Lowest F_L 8.5 N.");
        assert_eq!(sentences(&["done.".to_string()]), "Done.");
        assert_eq!(sentences(&[]), "");
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
        assert!(
            h.contains("<td class=\"n\">10</td><td style=\"background:#c8f0c8\">light green</td>")
        );
        assert!(h.contains("<td class=\"n\">40</td><td>grey</td>"));
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
