//! A small XML writer for the MJCF file: elements with attributes in the order given,
//! comments, two-space indentation, escaped text. Nothing else (no namespaces, no text
//! nodes), which is all MJCF needs.

use std::fmt::Write;

/// An XML document being written, element by element.
#[derive(Debug, Default)]
pub struct XmlWriter {
    out: String,
    open: Vec<String>,
}

/// Escape `&`, `<`, `>` and `"` for an attribute value.
pub fn escape(s: &str) -> String {
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

impl XmlWriter {
    /// A document starting with the XML declaration.
    pub fn new() -> Self {
        XmlWriter { out: "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n".into(), open: Vec::new() }
    }

    fn indent(&mut self) {
        for _ in 0..self.open.len() {
            self.out.push_str("  ");
        }
    }

    fn tag(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.indent();
        self.out.push('<');
        self.out.push_str(name);
        for (k, v) in attrs {
            let _ = write!(self.out, " {k}=\"{}\"", escape(v));
        }
    }

    /// Open `<name a="..">`; close it with [`XmlWriter::close`].
    pub fn open(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.tag(name, attrs);
        self.out.push_str(">\n");
        self.open.push(name.to_string());
    }

    /// An empty element `<name a=".."/>`.
    pub fn empty(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.tag(name, attrs);
        self.out.push_str("/>\n");
    }

    /// Close the innermost open element.
    pub fn close(&mut self) {
        let name = self.open.pop().expect("close without open");
        self.indent();
        let _ = writeln!(self.out, "</{name}>");
    }

    /// A comment on its own line(s); `--` (not allowed in XML comments) becomes `- -`.
    pub fn comment(&mut self, text: &str) {
        let text = text.replace("--", "- -");
        for line in text.lines() {
            self.indent();
            let _ = writeln!(self.out, "<!-- {line} -->");
        }
    }

    /// An empty line (between sections).
    pub fn blank(&mut self) {
        self.out.push('\n');
    }

    /// The document; every element must be closed.
    pub fn finish(self) -> String {
        assert!(self.open.is_empty(), "unclosed elements: {:?}", self.open);
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_elements_attributes_and_comments() {
        let mut w = XmlWriter::new();
        w.open("a", &[("x", "1 & <2>".into())]);
        w.comment("a -- b\nsecond");
        w.empty("b", &[("q", "\"".into())]);
        w.close();
        let s = w.finish();
        assert!(s.contains("<a x=\"1 &amp; &lt;2&gt;\">\n"), "{s}");
        assert!(s.contains("  <!-- a - - b -->\n  <!-- second -->\n"), "{s}");
        assert!(s.contains("  <b q=\"&quot;\"/>\n</a>\n"), "{s}");
    }
}
