//! Where the FMU's start parameters come from: the resource location the importer
//! passes (a `file:` URI, percent-decoded on bytes) and the `parameters.toml` in it.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use crate::fmi::instance::fmi_name_of_key;
use crate::params::{Params, ParamsError};

/// The largest parameters.toml read: a real one is a few kB; anything larger is not a
/// parameter file (and a device such as /dev/zero would never end).
const MAX_PARAMETERS_FILE_BYTES: u64 = 1 << 20;

/// Why a resource location cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ResourceUriError {
    #[error("is empty")]
    Empty,
    #[error("is not a file URI (expected file:///path, file://localhost/path or file:/path)")]
    NotFile,
    #[error(
        "names the host {0:?}: only local files (file:///path, file://localhost/path) can be read"
    )]
    RemoteHost(String),
    #[error("has a bad percent escape at byte {0} (expected % and two hex digits)")]
    BadEscape(usize),
    #[error("decodes to a path with a NUL byte")]
    Nul,
}

/// `file:///p`, `file://localhost/p`, `file:/p` (RFC 8089; the scheme in any case) or a
/// plain absolute path, percent-decoded on bytes, to a local path.
pub fn resource_path(uri: &[u8]) -> Result<std::path::PathBuf, ResourceUriError> {
    use ResourceUriError::*;
    if uri.is_empty() {
        return Err(Empty);
    }
    let encoded: &[u8] = if uri.len() >= 5 && uri[..5].eq_ignore_ascii_case(b"file:") {
        let rest = &uri[5..];
        match rest.strip_prefix(b"//") {
            Some(auth) => {
                let end = auth.iter().position(|&b| b == b'/').unwrap_or(auth.len());
                let host = &auth[..end];
                if !(host.is_empty() || host.eq_ignore_ascii_case(b"localhost")) {
                    return Err(RemoteHost(String::from_utf8_lossy(host).into_owned()));
                }
                &auth[end..]
            }
            None if rest.starts_with(b"/") => rest,
            None => return Err(NotFile),
        }
    } else if uri.starts_with(b"/") {
        uri
    } else {
        return Err(NotFile);
    };
    let path = percent_decode(encoded)?;
    if path.contains(&0) {
        return Err(Nul);
    }
    Ok(path_from_bytes(path))
}

/// `%XX` to the byte XX; a `%` without two hex digits is an error.
fn percent_decode(b: &[u8]) -> Result<Vec<u8>, ResourceUriError> {
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let (Some(h), Some(l)) = (
                b.get(i + 1).copied().and_then(hex),
                b.get(i + 2).copied().and_then(hex),
            ) else {
                return Err(ResourceUriError::BadEscape(i));
            };
            out.push(h << 4 | l);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Ok(out)
}

#[cfg(unix)]
fn path_from_bytes(b: Vec<u8>) -> std::path::PathBuf {
    use std::os::unix::ffi::OsStringExt;
    std::ffi::OsString::from_vec(b).into()
}

#[cfg(not(unix))]
fn path_from_bytes(b: Vec<u8>) -> std::path::PathBuf {
    String::from_utf8_lossy(&b).into_owned().into()
}

/// Start parameters and, when they are the defaults for want of a usable location, the
/// warning that says so.
///
/// What a user expects: an FMU built with `--params` runs the lab's values or refuses to
/// start, never the defaults behind their back. So a location that exists with a
/// parameters.toml that cannot be read or is invalid is an error; a folder without one
/// is an FMU built without `--params` (defaults, silently); a null, malformed or missing
/// location means the importer lost the FMU's resources: the defaults run, with a
/// warning that names the location and says so.
pub fn start_params(resources: Option<&[u8]>) -> Result<(Params, Option<String>), String> {
    const DEFAULTS: &str = "the built-in TREES Lab defaults are used \
        (a resources/parameters.toml shipped in the FMU cannot be read)";
    let Some(uri) = resources else {
        return Ok((
            Params::trees_lab(),
            Some(format!("fmuResourceLocation is null: {DEFAULTS}")),
        ));
    };
    let shown = String::from_utf8_lossy(uri);
    let dir = match resource_path(uri) {
        Ok(d) => d,
        Err(e) => {
            let w = format!("fmuResourceLocation {shown:?} {e}: {DEFAULTS}");
            return Ok((Params::trees_lab(), Some(w)));
        }
    };
    if !dir.is_dir() {
        let w = format!(
            "fmuResourceLocation {shown:?} is not a folder ({}): {DEFAULTS}",
            dir.display()
        );
        return Ok((Params::trees_lab(), Some(w)));
    }
    let path = dir.join("parameters.toml");
    match std::fs::symlink_metadata(&path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok((Params::trees_lab(), None)),
        Err(e) => Err(format!("{}: {e}", path.display())),
        Ok(_) => read_parameters(&path).map(|p| (p, None)),
    }
}

/// A parameters.toml that exists: a regular file of plausible size, valid.
fn read_parameters(path: &std::path::Path) -> Result<Params, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{}: not a regular file", path.display()));
    }
    if meta.len() > MAX_PARAMETERS_FILE_BYTES {
        return Err(format!(
            "{}: {} bytes, larger than any parameter file ({MAX_PARAMETERS_FILE_BYTES} bytes at most)",
            path.display(),
            meta.len()
        ));
    }
    Params::from_file(path).map_err(|e| match &e {
        // the file's own key, and the FMI variable it sets
        ParamsError::Invalid { key, .. } => match fmi_name_of_key(key) {
            Some(name) => format!("{e} (FMI variable {name})"),
            None => e.to_string(),
        },
        _ => e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn resource_uris_are_parsed_on_bytes() {
        let p = |u: &[u8]| resource_path(u);
        let ok = |s: &str| Ok(PathBuf::from(s));
        assert_eq!(p(b"file:///a/b%20c"), ok("/a/b c"));
        assert_eq!(p(b"file://localhost/a/b"), ok("/a/b"));
        assert_eq!(p(b"FILE://LOCALHOST/a"), ok("/a"));
        assert_eq!(p(b"file:/a/%C3%A9"), ok("/a/\u{e9}"));
        assert_eq!(p(b"/plain/path"), ok("/plain/path"));
        use ResourceUriError::*;
        assert_eq!(p(b"file:///a%\xc3\xa9"), Err(BadEscape(2)));
        assert_eq!(p(b"file:///a%4"), Err(BadEscape(2)));
        assert_eq!(p(b"file:///a%00b"), Err(Nul));
        assert_eq!(p(b"file://server/a"), Err(RemoteHost("server".into())));
        assert_eq!(p(b"file:a"), Err(NotFile));
        assert_eq!(p(b"http://x/a"), Err(NotFile));
        assert_eq!(p(b""), Err(Empty));
    }
}
