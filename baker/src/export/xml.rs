//! Escaping text for the XML documents of the exports (MaterialX, Mitsuba 3).

/// Escapes text for an XML attribute value or element content.
pub(crate) fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Text safe inside an XML comment (no `--`).
pub(crate) fn xml_comment(s: &str) -> String {
    s.replace("--", "- -")
}
