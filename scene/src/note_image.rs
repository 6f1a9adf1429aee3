//! Images kept with a note (photographs of a crack, a chart of a survey): PNG or JPEG files that
//! a browser shows as they are. restauro never decodes them; it checks that each is what its
//! name says (the file's signature, ISO/IEC 15948 §5.2 for PNG, ITU-T T.81 §B.1.1.2 for JPEG's
//! SOI marker followed by a marker segment), so that the studio serves nothing else under an
//! image's media type.

/// The extensions a note's image may have.
pub const EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// The most images one note may hold.
pub const MAX_PER_NOTE: usize = 32;

/// The largest image a note may hold, in bytes.
pub const MAX_BYTES: usize = 16 << 20;

/// The media type of an image with the given `extension` (lower case) whose first bytes are
/// `bytes`, or `None` when the bytes are not an image of that kind.
pub fn media_type(extension: &str, bytes: &[u8]) -> Option<&'static str> {
    const PNG: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];
    match extension {
        "png" if bytes.starts_with(&PNG) && bytes.get(12..16) == Some(b"IHDR") => Some("image/png"),
        "jpg" | "jpeg" if bytes.starts_with(&[0xff, 0xd8, 0xff]) => Some("image/jpeg"),
        _ => None,
    }
}

/// What a file named `.extension` with the wrong content is refused with.
pub fn not_an_image(extension: &str) -> String {
    format!(
        "not a {} file (its first bytes are not that format's signature); send a PNG or JPEG image",
        if extension == "png" { "PNG" } else { "JPEG" }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signatures_are_told_apart() {
        let png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01";
        assert_eq!(media_type("png", png), Some("image/png"));
        assert_eq!(media_type("jpg", png), None);
        assert_eq!(media_type("jpeg", b"\xff\xd8\xff\xe0\0\x10JFIF"), Some("image/jpeg"));
        assert_eq!(media_type("png", b"\xff\xd8\xff\xe0"), None);
        assert_eq!(media_type("png", b"<svg onload=alert(1)>"), None);
        assert_eq!(media_type("svg", b"<svg/>"), None);
        assert_eq!(media_type("png", b"\x89PNG\r\n\x1a\n"), None, "no IHDR: cut short");
    }
}
