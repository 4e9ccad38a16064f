//! One self-contained `report.html`: inline CSS, inline SVG, no external resources (the
//! only script is the body animation's, [`super::body`]; everything else reads without it), with a summary box (status, stop reason, iterations, time) at the top, a
//! list of contents, then the sections in order (paragraphs, tables, figures).
//!
//! Text (titles, paragraphs, table cells) is escaped; SVG strings are embedded as given
//! (an XML declaration in front is dropped), so they must come from a trusted source such
//! as [`super::plot`].

use super::table::Table;
use super::{escape_xml, ReportError};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// How the summary box is coloured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tone {
    /// Green: the run did what was asked (e.g. converged).
    Good,
    /// Amber: a result exists but is not what was asked (e.g. an iteration limit).
    Warning,
    /// Red: the run failed.
    Bad,
    /// Grey: no judgement.
    #[default]
    Neutral,
}

/// The summary box at the top of the report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Summary {
    /// Status in a word or two, e.g. "converged".
    pub status: String,
    /// Colour of the box.
    pub tone: Tone,
    /// Why the run stopped, in words.
    pub stop_reason: String,
    /// Iterations, if the run iterates.
    pub iterations: Option<usize>,
    /// Wall-clock time (s).
    pub time_s: Option<f64>,
    /// Further `(name, value)` lines, in order.
    pub extra: Vec<(String, String)>,
}

impl Summary {
    /// A summary with a status, its tone and the stop reason.
    pub fn new(status: impl Into<String>, tone: Tone, stop_reason: impl Into<String>) -> Self {
        Self {
            status: status.into(),
            tone,
            stop_reason: stop_reason.into(),
            ..Self::default()
        }
    }
}

/// A section: a heading, then its paragraphs, tables and figures.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Section {
    /// Heading.
    pub heading: String,
    /// Paragraphs of plain text (escaped, not interpreted as HTML).
    pub paragraphs: Vec<String>,
    /// Tables.
    pub tables: Vec<Table>,
    /// SVG documents (e.g. [`super::plot::LinePlot::to_svg`] or [`super::plot::grid`]), or
    /// trusted HTML figure fragments ([`super::body::BodyAnimation::to_html`]).
    pub svgs: Vec<String>,
}

/// A whole report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Report {
    /// Title of the page.
    pub title: String,
    /// The box at the top.
    pub summary: Summary,
    /// Sections, in order.
    pub sections: Vec<Section>,
}

const CSS: &str = "\
body{margin:0;background:#f6f7f9;color:#1d232b;font:15px/1.5 'DejaVu Sans','Liberation Sans',Arial,Helvetica,sans-serif}
main{max-width:1100px;margin:0 auto;padding:24px 28px 48px;background:#fff;min-height:100vh;box-sizing:border-box}
h1{font-size:1.6em;margin:0 0 16px}
h2{font-size:1.25em;margin:32px 0 10px;padding-bottom:4px;border-bottom:1px solid #dde1e6}
.summary{border:1px solid;border-left-width:6px;border-radius:4px;padding:10px 16px;margin:0 0 20px}
.summary.good{border-color:#2e7d32;background:#eef7ee}
.summary.warning{border-color:#b26a00;background:#fff6e5}
.summary.bad{border-color:#c62828;background:#fdecea}
.summary.neutral{border-color:#6b7785;background:#f1f3f5}
.summary .status{font-size:1.2em;font-weight:bold;margin:0 0 6px}
.summary dl{display:grid;grid-template-columns:max-content auto;gap:2px 16px;margin:0}
.summary dt{color:#4a5563}
.summary dd{margin:0}
nav ol{margin:0 0 8px;padding-left:22px}
.table-wrap{overflow-x:auto}
table{border-collapse:collapse;margin:12px 0 18px;font-size:0.92em}
caption{text-align:left;font-weight:bold;padding:0 0 6px}
th,td{border:1px solid #d5dae0;padding:4px 10px;text-align:left;vertical-align:top}
thead th{background:#eef1f4}
tbody th{font-weight:normal;background:#fafbfc}
td{font-variant-numeric:tabular-nums;white-space:nowrap}
figure{margin:12px 0 20px;overflow-x:auto}
figure svg{max-width:100%;height:auto;display:block}
.anim .frame{display:none}
.anim .frame.on{display:inline}
.anim-controls{margin:4px 0 8px;display:flex;gap:10px;align-items:center}
.anim-scrub{flex:1;max-width:420px}
@media print{.anim{display:none}}
";

/// Wall-clock seconds as "0.42 s", "12.3 s" or "3 min 05 s".
fn format_duration(s: f64) -> String {
    if !s.is_finite() {
        return format!("{s}");
    }
    if s < 10.0 {
        format!("{s:.2} s")
    } else if s < 120.0 {
        format!("{s:.1} s")
    } else {
        let total = s.round() as u64;
        let (h, m, sec) = (total / 3600, (total / 60) % 60, total % 60);
        if h > 0 {
            format!("{h} h {m:02} min {sec:02} s")
        } else {
            format!("{m} min {sec:02} s")
        }
    }
}

/// An SVG document without a leading XML declaration.
fn strip_xml_declaration(svg: &str) -> &str {
    let t = svg.trim_start();
    if t.starts_with("<?xml") {
        t.find("?>").map(|i| t[i + 2..].trim_start()).unwrap_or(t)
    } else {
        t
    }
}

impl Report {
    /// The report as one HTML document.
    pub fn to_html(&self) -> String {
        let mut out = String::new();
        let title = escape_xml(&self.title);
        out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
        out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        writeln!(
            out,
            "<title>{title}</title>\n<style>\n{CSS}</style>\n</head>\n<body>\n<main>"
        )
        .ok();
        writeln!(out, "<h1>{title}</h1>").ok();

        let s = &self.summary;
        let tone = match s.tone {
            Tone::Good => "good",
            Tone::Warning => "warning",
            Tone::Bad => "bad",
            Tone::Neutral => "neutral",
        };
        writeln!(out, "<div class=\"summary {tone}\" id=\"summary\">").ok();
        writeln!(
            out,
            "<p class=\"status\">{}</p>\n<dl>",
            escape_xml(&s.status)
        )
        .ok();
        let mut item = |k: &str, v: &str| {
            writeln!(out, "<dt>{}</dt><dd>{}</dd>", escape_xml(k), escape_xml(v)).ok();
        };
        item("stop reason", &s.stop_reason);
        if let Some(n) = s.iterations {
            item("iterations", &n.to_string());
        }
        if let Some(t) = s.time_s {
            item("time", &format_duration(t));
        }
        for (k, v) in &s.extra {
            item(k, v);
        }
        out.push_str("</dl>\n</div>\n");

        if self.sections.len() > 1 {
            out.push_str("<nav>\n<ol>\n");
            for (i, sec) in self.sections.iter().enumerate() {
                writeln!(
                    out,
                    "<li><a href=\"#section-{}\">{}</a></li>",
                    i + 1,
                    escape_xml(&sec.heading)
                )
                .ok();
            }
            out.push_str("</ol>\n</nav>\n");
        }
        for (i, sec) in self.sections.iter().enumerate() {
            writeln!(
                out,
                "<section id=\"section-{}\">\n<h2>{}</h2>",
                i + 1,
                escape_xml(&sec.heading)
            )
            .ok();
            for p in &sec.paragraphs {
                writeln!(out, "<p>{}</p>", escape_xml(p)).ok();
            }
            for t in &sec.tables {
                out.push_str("<div class=\"table-wrap\">\n");
                out.push_str(&t.to_html());
                out.push_str("</div>\n");
            }
            for svg in &sec.svgs {
                out.push_str("<figure>\n");
                out.push_str(strip_xml_declaration(svg).trim_end());
                out.push_str("\n</figure>\n");
            }
            out.push_str("</section>\n");
        }
        out.push_str("</main>\n</body>\n</html>\n");
        out
    }

    /// Write `report.html` into the folder `dir` (which must exist); returns its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, ReportError> {
        let path = dir.join("report.html");
        std::fs::write(&path, self.to_html()).map_err(|source| ReportError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(path)
    }
}
