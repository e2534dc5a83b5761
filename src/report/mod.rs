//! Figures (plotters) and report pages. Everything here reads results; nothing computes
//! physics.

pub mod closed_loop;
mod device;
pub mod diagnose;
mod diagnose_causes;
mod diagnose_model_error;
pub use diagnose_model_error::MODEL_ERROR_FIGURES;
pub mod identify;
pub mod page;
pub mod plot;
pub mod read;
mod section4;
mod summary;

/// Why a report could not be written; every variant names the path.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("{path}: cannot create: {source}")]
    CreateDir {
        path: String,
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// Create the report folder `dir`.
pub(crate) fn create_dir(dir: &std::path::Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| ReportError::CreateDir {
        path: dir.display().to_string(),
        source,
    })
}

/// `s` made safe as HTML text or a quoted attribute value: `& < > " '` escaped. Every
/// string from outside the program (campaign and test names, file names, messages that
/// quote them) goes through it before it reaches a page.
pub fn escape_html(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `s` as a Markdown code span: a backtick in it (which would end the span and let the
/// rest render as Markdown or HTML) becomes `'`.
pub fn markdown_code(s: &str) -> String {
    format!("`{}`", s.replace('`', "'"))
}

/// A file name made from user text (a test name): only ASCII letters, digits, `-`, `_`
/// and `.` are kept, anything else (`/`, `..` separators, quotes, spaces) becomes `_`, so
/// the file stays inside the report folder and its name is safe in a link.
pub fn safe_file_name(s: &str) -> String {
    let name: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    name.trim_start_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_is_escaped_and_file_names_stay_inside() {
        assert_eq!(
            escape_html("<img src=x onerror=\"a&b\">'"),
            "&lt;img src=x onerror=&quot;a&amp;b&quot;&gt;&#39;"
        );
        assert_eq!(safe_file_name("../../etc/x\"y.png"), "_.._etc_x_y.png");
        assert_eq!(safe_file_name(".hidden"), "hidden");
        assert_eq!(markdown_code("a`<b>"), "`a'<b>`");
    }
}
