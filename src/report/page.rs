//! A report page as sections (a title, an optional figure, text, an optional table),
//! rendered once as Markdown (README.md) and once as HTML (index.html). Every string
//! from outside the program is escaped here.

use super::escape_html;
use std::fmt::Write as _;

/// A table of text cells.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column names and no rows yet.
    pub fn new(header: &[&str]) -> Table {
        Table {
            header: header.iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Add a row (one cell per column).
    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }
}

/// One section of a page.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Section {
    pub title: String,
    /// A figure's file name in the report folder.
    pub figure: Option<String>,
    /// Paragraphs separated by blank lines; a paragraph of several lines is shown as
    /// preformatted text (aligned columns of the command line's blocks).
    pub text: String,
    pub tables: Vec<Table>,
}

impl Section {
    /// A section of text and a figure.
    pub fn figure(title: impl Into<String>, figure: impl Into<String>, text: String) -> Section {
        Section {
            title: title.into(),
            figure: Some(figure.into()),
            text,
            tables: Vec::new(),
        }
    }

    /// A section of text and tables.
    pub fn tables(title: impl Into<String>, text: String, tables: Vec<Table>) -> Section {
        Section {
            title: title.into(),
            figure: None,
            text,
            tables,
        }
    }
}

/// Markdown text: `& < >` escaped (no live markup; quotes stay readable).
fn markdown_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A Markdown table cell: `|` would end it, a line break would end the row.
pub(crate) fn markdown_cell(s: &str) -> String {
    markdown_text(s).replace('|', "\\|").replace('\n', " ")
}

pub(crate) fn markdown_table(t: &Table, md: &mut String) {
    let row = |cells: &[String]| {
        let cells: Vec<String> = cells.iter().map(|c| markdown_cell(c)).collect();
        format!("| {} |\n", cells.join(" | "))
    };
    md.push_str(&row(&t.header));
    let _ = writeln!(md, "|{}", "---|".repeat(t.header.len()));
    for r in &t.rows {
        md.push_str(&row(r));
    }
    md.push('\n');
}

/// The page as Markdown.
pub fn markdown(title: &str, sections: &[Section]) -> String {
    let mut md = format!("# {}\n\n", markdown_text(title));
    for s in sections {
        let _ = write!(md, "## {}\n\n", markdown_cell(&s.title));
        if let Some(f) = &s.figure {
            let _ = write!(md, "![{}]({f})\n\n", markdown_cell(&s.title));
        }
        for p in s.text.split("\n\n").filter(|p| !p.trim().is_empty()) {
            match p.trim_end().contains('\n') {
                // a fence inside would end the block early
                true => {
                    let _ = write!(md, "```\n{}\n```\n\n", p.trim_end().replace("```", "'''"));
                }
                false => {
                    let _ = write!(md, "{}\n\n", markdown_text(p.trim()));
                }
            }
        }
        for t in &s.tables {
            markdown_table(t, &mut md);
        }
    }
    md
}

pub(crate) fn html_table(t: &Table, html: &mut String) {
    html.push_str("<table><tr>");
    for h in &t.header {
        let _ = write!(html, "<th>{}</th>", escape_html(h));
    }
    html.push_str("</tr>");
    for r in &t.rows {
        html.push_str("<tr>");
        for c in r {
            let _ = write!(html, "<td>{}</td>", escape_html(c));
        }
        html.push_str("</tr>");
    }
    html.push_str("</table>");
}

/// The page as HTML.
pub fn html(title: &str, sections: &[Section]) -> String {
    let mut html = format!(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>{0}</title>\
         <style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}table{{border-collapse:collapse;margin:6px 0}}\
         td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}td:first-child{{text-align:left}}\
         img{{max-width:100%}}pre{{white-space:pre-wrap}}</style></head><body><h1>{0}</h1>",
        escape_html(title)
    );
    for s in sections {
        let _ = write!(html, "<h2>{}</h2>", escape_html(&s.title));
        if let Some(f) = &s.figure {
            let _ = write!(html, "<img src=\"{}\">", escape_html(f));
        }
        for p in s.text.split("\n\n").filter(|p| !p.trim().is_empty()) {
            match p.trim_end().contains('\n') {
                true => {
                    let _ = write!(html, "<pre>{}</pre>", escape_html(p.trim_end()));
                }
                false => {
                    let _ = write!(html, "<p>{}</p>", escape_html(p.trim()));
                }
            }
        }
        for t in &s.tables {
            html_table(t, &mut html);
        }
    }
    html.push_str("</body></html>\n");
    html
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_and_text_render_escaped_in_both_forms() {
        let mut t = Table::new(&["test", "file"]);
        t.push(vec!["<b>".into(), "a|b.csv".into()]);
        let s = vec![Section::tables(
            "What <was> read",
            "one\n\ntwo\nlines".into(),
            vec![t],
        )];
        let h = html("c", &s);
        assert!(h.contains("<td>&lt;b&gt;</td><td>a|b.csv</td>"), "{h}");
        assert!(h.contains("<p>one</p><pre>two\nlines</pre>"), "{h}");
        let m = markdown("c", &s);
        assert!(m.contains("| &lt;b&gt; | a\\|b.csv |"), "{m}");
        assert!(m.contains("|---|---|"), "{m}");
        assert!(m.contains("```\ntwo\nlines\n```"), "{m}");
    }
}
