//! A builder for one self-contained HTML page: headings, paragraphs, tables,
//! call-out notes and images embedded as base64 data URIs, with inline CSS.
//! The page loads nothing from the network, and this module reads and writes no file: the
//! images' bytes come from the caller when the page is rendered to text.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::PlotError;

/// Escapes `&`, `<`, `>`, `"` and `'` so `text` can be placed in HTML
/// element content or a quoted attribute value.
pub fn html_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// Text of the page as HTML: escaped ([`html_escape`]), then each pair of backticks around
/// a span (`` `deflex plot` ``, markdown's inline code) made a `<code>` element. Escaping first
/// means nothing in `text` can open a tag; an unpaired backtick stays as it is.
pub fn inline_html(text: &str) -> String {
    let escaped = html_escape(text);
    let parts: Vec<&str> = escaped.split('`').collect();
    // An odd number of parts: every backtick has its pair.
    let pairs = (parts.len() - 1) / 2;
    let mut out = String::with_capacity(escaped.len() + pairs * 13);
    for (i, part) in parts.iter().enumerate() {
        if i == 0 {
            out.push_str(part);
        } else if i > 2 * pairs {
            // After the last pair: the unpaired backtick, kept.
            out.push('`');
            out.push_str(part);
        } else if i % 2 == 1 {
            let _ = write!(out, "<code>{part}");
        } else {
            let _ = write!(out, "</code>{part}");
        }
    }
    out
}

/// Text for an attribute (an image's `alt`): escaped, with the backticks of code spans removed.
fn plain_attribute(text: &str) -> String {
    html_escape(&text.replace('`', ""))
}

#[derive(Debug, Clone, PartialEq)]
enum Block {
    Section(String),
    Subsection(String),
    Contents,
    Files(Vec<FileLink>),
    Paragraph(String),
    Note(String),
    Preformatted(String),
    Table {
        headers: Vec<String>,
        rows: Vec<Vec<String>>,
    },
    Image {
        path: PathBuf,
        caption: String,
    },
}

/// A link to a file beside the page, with what it holds (see [`HtmlReport::files`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileLink {
    /// Path relative to the page (`plan.csv`, `forming_open/log.csv`): letters, digits, `.`,
    /// `_`, `-` and `/` only, no `..`, not absolute. Checked when the page is rendered.
    pub href: String,
    /// One line on what the file holds.
    pub description: String,
}

impl FileLink {
    /// A link to `href` described by `description`.
    pub fn new(href: impl Into<String>, description: impl Into<String>) -> Self {
        FileLink {
            href: href.into(),
            description: description.into(),
        }
    }
}

/// Whether `href` is a plain relative path inside the page's folder.
fn relative_inside(href: &str) -> bool {
    !href.is_empty()
        && !href.starts_with('/')
        && href
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-' | '/'))
        && href.split('/').all(|part| !part.is_empty() && part != "..")
}

/// Anchor ids of the (sub)sections, in order: a slug of the heading, made unique.
fn section_ids(blocks: &[Block]) -> Vec<String> {
    let mut ids: Vec<String> = Vec::new();
    for block in blocks {
        let (Block::Section(t) | Block::Subsection(t)) = block else {
            continue;
        };
        let mut slug = String::new();
        for c in t.chars() {
            if c.is_ascii_alphanumeric() {
                slug.push(c.to_ascii_lowercase());
            } else if !slug.ends_with('-') && !slug.is_empty() {
                slug.push('-');
            }
        }
        let slug = slug.trim_end_matches('-');
        let base = if slug.is_empty() { "section" } else { slug };
        let mut id = base.to_string();
        let mut k = 2;
        while ids.contains(&id) {
            id = format!("{base}-{k}");
            k += 1;
        }
        ids.push(id);
    }
    ids
}

/// Builder of a self-contained HTML report.
///
/// Text is HTML-escaped. Images are named by their paths; when the page is rendered
/// ([`HtmlReport::render`]) the caller's loader gives each one's bytes, which are embedded as
/// base64 data URIs, so the page can be moved, mailed or opened offline. Writing the page is
/// the caller's (deflex's application layer writes it whole or not at all).
///
/// ```
/// use deflex_plot::HtmlReport;
/// let mut r = HtmlReport::new("Calibration report");
/// r.note("SIMULATED data: no robot was measured.")
///     .section("Prediction error")
///     .paragraph("Error over the test grid.")
///     .table(&["axis", "RMSE [mm]"], &[vec!["x".into(), "0.12".into()]])
///     .image("heatmap.png", "Fig. 1: error norm over the grid");
/// // The figure's bytes, from wherever the caller keeps them (here: a PNG signature).
/// let html = r.render(|_path| Ok(b"\x89PNG\r\n\x1a\n".to_vec())).unwrap();
/// assert!(html.contains("<img src=\"data:image/png;base64,iVBORw0KGgo=\""));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct HtmlReport {
    title: String,
    blocks: Vec<Block>,
}

const CSS: &str = "\
body{font-family:-apple-system,'Segoe UI',Roboto,'DejaVu Sans',Helvetica,Arial,sans-serif;\
max-width:1120px;margin:2em auto;padding:0 1.2em;color:#222;line-height:1.5;background:#fff;\
overflow-wrap:anywhere}\
h1{font-size:1.8em;border-bottom:2px solid #1f77b4;padding-bottom:.25em}\
h2{font-size:1.35em;margin-top:1.8em;border-bottom:1px solid #ddd;padding-bottom:.15em}\
table{border-collapse:collapse;font-size:.95em}\
div.table-wrap{overflow-x:auto;max-width:100%;margin:1em 0}\
div.table-wrap th,div.table-wrap td{overflow-wrap:normal}\
img{max-width:100%;height:auto}\
code{overflow-wrap:anywhere}\
th,td{border:1px solid #ccc;padding:.35em .75em;text-align:left}\
th{background:#f0f4f8}tr:nth-child(even) td{background:#fafafa}\
td.num{text-align:right;font-variant-numeric:tabular-nums}\
figure{margin:1.5em 0;text-align:center}\
figure img{max-width:100%;height:auto;border:1px solid #e4e4e4}\
figcaption{font-size:.92em;color:#555;margin-top:.4em}\
.note{border-left:5px solid #d62728;background:#fdf1f1;padding:.6em 1em;margin:1em 0;font-weight:600}\
pre{background:#f6f8fa;padding:.8em;overflow-x:auto;font-size:.9em}\
footer{margin-top:3em;font-size:.8em;color:#888}\
h3{font-size:1.12em;margin-top:1.4em}\
nav.contents{background:#f6f8fa;border:1px solid #e1e4e8;padding:.6em 1.2em;margin:1em 0}\
nav.contents ul{list-style:none;margin:.2em 0;padding-left:1.2em}nav.contents a,ul.files a{color:#1f5f99}\
ul.files code{font-size:.95em}";

impl HtmlReport {
    /// A new, empty report whose page title and top heading are `title`.
    pub fn new(title: impl Into<String>) -> Self {
        HtmlReport {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// Starts a section with a second-level heading.
    pub fn section(&mut self, heading: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Section(heading.into()));
        self
    }

    /// Starts a subsection with a third-level heading (listed under its section by
    /// [`HtmlReport::contents`]).
    pub fn subsection(&mut self, heading: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Subsection(heading.into()));
        self
    }

    /// Places the table of contents here: a linked list of every section (and its
    /// subsections) of the page, including those added later.
    pub fn contents(&mut self) -> &mut Self {
        self.blocks.push(Block::Contents);
        self
    }

    /// Adds a list of links to files beside the page, each with its one-line description.
    /// Every `href` must be a plain relative path inside the page's folder ([`FileLink`]);
    /// this is checked when the page is rendered.
    pub fn files(&mut self, links: &[FileLink]) -> &mut Self {
        self.blocks.push(Block::Files(links.to_vec()));
        self
    }

    /// Adds a paragraph of text.
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Adds a highlighted call-out, e.g. `"SIMULATED"` for results not
    /// measured on a real robot.
    pub fn note(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Note(text.into()));
        self
    }

    /// Adds preformatted (monospace) text, e.g. a configuration dump.
    pub fn preformatted(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Preformatted(text.into()));
        self
    }

    /// Adds a table. Every row must have as many cells as there are headers;
    /// this is checked when the page is rendered. Cells that parse as numbers
    /// are right-aligned.
    pub fn table(&mut self, headers: &[&str], rows: &[Vec<String>]) -> &mut Self {
        self.blocks.push(Block::Table {
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: rows.to_vec(),
        });
        self
    }

    /// Adds an image (PNG, SVG, JPEG or GIF, by extension) with a caption. Its bytes are asked
    /// of the loader passed to [`HtmlReport::render`], by `path`, and embedded.
    pub fn image(&mut self, path: impl AsRef<Path>, caption: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Image {
            path: path.as_ref().to_path_buf(),
            caption: caption.into(),
        });
        self
    }

    /// Renders the page to a string, asking `images` for the bytes of each image by the path it
    /// was added with ([`HtmlReport::image`]); a page without images never calls it. Errors
    /// name the image or table that is at fault (for a table, the path is empty); the loader's
    /// failure is [`PlotError::Io`] naming the image.
    pub fn render(
        &self,
        mut images: impl FnMut(&Path) -> std::io::Result<Vec<u8>>,
    ) -> Result<String, PlotError> {
        let mut h = String::new();
        let title = plain_attribute(&self.title);
        h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        let _ = writeln!(h, "<title>{title}</title>");
        let _ = writeln!(h, "<style>{CSS}</style>\n</head>\n<body>");
        let _ = writeln!(h, "<h1>{}</h1>", inline_html(&self.title));
        let ids = section_ids(&self.blocks);
        let mut next_id = ids.iter();
        for block in &self.blocks {
            match block {
                Block::Section(t) => {
                    let id = next_id.next().map(String::as_str).unwrap_or_default();
                    let _ = writeln!(h, "<h2 id=\"{id}\">{}</h2>", inline_html(t));
                }
                Block::Subsection(t) => {
                    let id = next_id.next().map(String::as_str).unwrap_or_default();
                    let _ = writeln!(h, "<h3 id=\"{id}\">{}</h3>", inline_html(t));
                }
                Block::Contents => render_contents(&mut h, &self.blocks, &ids),
                Block::Files(links) => render_files(&mut h, links)?,
                Block::Paragraph(t) => {
                    let _ = writeln!(h, "<p>{}</p>", inline_html(t));
                }
                Block::Note(t) => {
                    let _ = writeln!(h, "<div class=\"note\">{}</div>", inline_html(t));
                }
                Block::Preformatted(t) => {
                    let _ = writeln!(h, "<pre>{}</pre>", html_escape(t));
                }
                Block::Table { headers, rows } => render_table(&mut h, headers, rows)?,
                Block::Image { path, caption } => render_image(&mut h, path, caption, &mut images)?,
            }
        }
        let _ = writeln!(
            h,
            "<footer>Generated by deflex {}.</footer>\n</body>\n</html>",
            env!("CARGO_PKG_VERSION")
        );
        Ok(h)
    }
}

fn render_contents(h: &mut String, blocks: &[Block], ids: &[String]) {
    h.push_str("<nav class=\"contents\"><strong>Contents</strong>\n<ul>\n");
    let mut ids = ids.iter();
    let mut open_sub = false;
    let mut any_section = false;
    for block in blocks {
        match block {
            Block::Section(t) => {
                let id = ids.next().map(String::as_str).unwrap_or_default();
                if open_sub {
                    h.push_str("</ul>");
                    open_sub = false;
                }
                if any_section {
                    h.push_str("</li>\n");
                }
                let _ = write!(h, "<li><a href=\"#{id}\">{}</a>", inline_html(t));
                any_section = true;
            }
            Block::Subsection(t) => {
                let id = ids.next().map(String::as_str).unwrap_or_default();
                if !open_sub {
                    h.push_str("<ul>");
                    open_sub = true;
                }
                let _ = write!(h, "<li><a href=\"#{id}\">{}</a></li>", inline_html(t));
            }
            _ => {}
        }
    }
    if open_sub {
        h.push_str("</ul>");
    }
    if any_section {
        h.push_str("</li>\n");
    }
    h.push_str("</ul></nav>\n");
}

fn render_files(h: &mut String, links: &[FileLink]) -> Result<(), PlotError> {
    h.push_str("<ul class=\"files\">\n");
    for link in links {
        if !relative_inside(&link.href) {
            return Err(PlotError::InvalidInput {
                path: PathBuf::from(&link.href),
                reason: "a file link must be a relative path inside the page's folder \
                         (letters, digits, '.', '_', '-', '/'; no '..')"
                    .into(),
            });
        }
        let href = html_escape(&link.href);
        let _ = writeln!(
            h,
            "<li><a href=\"{href}\"><code>{href}</code></a>: {}</li>",
            inline_html(&link.description)
        );
    }
    h.push_str("</ul>\n");
    Ok(())
}

fn looks_numeric(cell: &str) -> bool {
    let t = cell.trim();
    !t.is_empty()
        && t.trim_start_matches(['+', '-', '±'])
            .trim_end_matches('%')
            .parse::<f64>()
            .is_ok()
}

fn render_table(h: &mut String, headers: &[String], rows: &[Vec<String>]) -> Result<(), PlotError> {
    for (i, row) in rows.iter().enumerate() {
        if !headers.is_empty() && row.len() != headers.len() {
            return Err(PlotError::InvalidInput {
                path: PathBuf::new(),
                reason: format!(
                    "table row {i} has {} cells but there are {} headers ({})",
                    row.len(),
                    headers.len(),
                    headers.join(", ")
                ),
            });
        }
    }
    h.push_str("<div class=\"table-wrap\"><table>\n");
    if !headers.is_empty() {
        h.push_str("<thead><tr>");
        for c in headers {
            let _ = write!(h, "<th>{}</th>", inline_html(c));
        }
        h.push_str("</tr></thead>\n");
    }
    h.push_str("<tbody>\n");
    for row in rows {
        h.push_str("<tr>");
        for c in row {
            let class = if looks_numeric(c) {
                " class=\"num\""
            } else {
                ""
            };
            let _ = write!(h, "<td{class}>{}</td>", inline_html(c));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table></div>\n");
    Ok(())
}

fn render_image(
    h: &mut String,
    path: &Path,
    caption: &str,
    images: &mut impl FnMut(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<(), PlotError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let mime = match ext.as_deref() {
        Some("png") => "image/png",
        Some("svg") => "image/svg+xml",
        Some("jpg" | "jpeg") => "image/jpeg",
        Some("gif") => "image/gif",
        _ => {
            return Err(PlotError::UnsupportedFormat {
                path: path.to_path_buf(),
                expected: ".png, .svg, .jpg, .jpeg or .gif",
            });
        }
    };
    let bytes = images(path).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let (alt, cap) = (plain_attribute(caption), inline_html(caption));
    let _ = writeln!(
        h,
        "<figure><img src=\"data:{mime};base64,{}\" alt=\"{alt}\"><figcaption>{cap}</figcaption></figure>",
        data_encoding::BASE64.encode(&bytes)
    );
    Ok(())
}
