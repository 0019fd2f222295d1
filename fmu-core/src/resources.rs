//! `fmuResourceLocation`: the URI of the unpacked FMU's `resources/`
//! folder, as a path. FMI 2.0 (section 2.1.5) gives it as a URI
//! ("file:///C:/temp/MyFMU/resources", "file:/home/me/fmu/resources"); hosts
//! differ in the number of slashes, a trailing slash and percent-encoding.

use std::path::PathBuf;

/// The folder of a `file:` URI (`file:/p`, `file:///p`,
/// `file://localhost/p`, percent-encoded, with or without a trailing
/// slash); `None` for another scheme or a malformed escape.
pub fn resource_dir(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = match rest.strip_prefix("//") {
        // file://host/path: only the local host is a path here.
        Some(authority_and_path) => {
            let slash = authority_and_path.find('/')?;
            let (host, path) = authority_and_path.split_at(slash);
            if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
                return None;
            }
            path
        }
        None => rest,
    };
    let decoded = percent_decode(path)?;
    // file:///C:/dir: the drive letter follows the slash on Windows.
    let bytes = decoded.as_bytes();
    let windows_drive = bytes.len() >= 3 && bytes[0] == b'/' && bytes[2] == b':';
    let decoded = if cfg!(windows) && windows_drive {
        decoded[1..].to_string()
    } else {
        decoded
    };
    let trimmed = decoded.trim_end_matches('/');
    Some(PathBuf::from(if trimmed.is_empty() {
        "/"
    } else {
        trimmed
    }))
}

fn percent_decode(s: &str) -> Option<String> {
    let mut out = Vec::with_capacity(s.len());
    let mut bytes = s.bytes();
    while let Some(b) = bytes.next() {
        if b == b'%' {
            let hex = [bytes.next()?, bytes.next()?];
            let hex = std::str::from_utf8(&hex).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
        } else {
            out.push(b);
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_forms_hosts_send() {
        for uri in [
            "file:///tmp/fmu/resources",
            "file:///tmp/fmu/resources/",
            "file:/tmp/fmu/resources",
            "file://localhost/tmp/fmu/resources",
        ] {
            assert_eq!(
                resource_dir(uri),
                Some(PathBuf::from("/tmp/fmu/resources")),
                "{uri}"
            );
        }
        assert_eq!(
            resource_dir("file:///tmp/my%20fmu/resources"),
            Some(PathBuf::from("/tmp/my fmu/resources"))
        );
    }

    #[test]
    fn what_is_not_a_local_folder() {
        assert_eq!(resource_dir("http://example.org/resources"), None);
        assert_eq!(resource_dir("file://otherhost/resources"), None);
        assert_eq!(resource_dir("file:///tmp/bad%2"), None);
        assert_eq!(resource_dir("file:///tmp/bad%zz"), None);
    }
}
