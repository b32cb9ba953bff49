//! fmuResourceLocation (2.1.5 fmi2Instantiate): a `file` URI (RFC 8089) to a path.

use std::path::PathBuf;

/// The path a `file:` URI names: `file:///p`, `file:/p` and `file://localhost/p`, with
/// percent-escapes (`%20`, `%25`, ...) decoded. A bare absolute path is taken as is.
pub fn file_uri_to_path(uri: &str) -> Result<PathBuf, String> {
    let Some(rest) = uri.strip_prefix("file:") else {
        if uri.starts_with('/') {
            return Ok(PathBuf::from(uri));
        }
        return Err(format!("resource location '{uri}' is not a file URI"));
    };
    let path = match rest.strip_prefix("//") {
        Some(auth_path) => {
            let split = auth_path.find('/').unwrap_or(auth_path.len());
            let host = &auth_path[..split];
            if !host.is_empty() && !host.eq_ignore_ascii_case("localhost") {
                return Err(format!("resource location '{uri}' names host '{host}'; only local files are supported"));
            }
            &auth_path[split..]
        }
        None => rest,
    };
    if !path.starts_with('/') {
        return Err(format!("resource location '{uri}' has no absolute path"));
    }
    Ok(PathBuf::from(percent_decode(path).ok_or_else(|| format!("resource location '{uri}' has a bad %-escape"))?))
}

/// Decode `%XX` escapes; None on a malformed escape or non-UTF-8 result.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_file_uri_spellings_and_escapes_decode() {
        let want = PathBuf::from("/tmp/a b%/res");
        assert_eq!(file_uri_to_path("file:///tmp/a%20b%25/res").unwrap(), want);
        assert_eq!(file_uri_to_path("file:/tmp/a%20b%25/res").unwrap(), want);
        assert_eq!(file_uri_to_path("file://localhost/tmp/a%20b%25/res").unwrap(), want);
        assert!(file_uri_to_path("file://server/x").is_err());
        assert!(file_uri_to_path("file:///x%2").is_err());
        assert!(file_uri_to_path("http://x/y").is_err());
    }
}
