//! The XML of XDF's headers and footers: escaping and writing StreamHeaders, and a small tree of
//! parsed XML whose errors point at the byte at fault (read into XDF's types in [`super::read`]).

use std::fmt::Write as _;

use super::types::*;

pub(super) fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c => o.push(c),
        }
    }
    o
}

/// Why `s` cannot go into the XML header, if it cannot.
pub(super) fn xml_text_problem(s: &str) -> Option<&'static str> {
    if s.chars()
        .any(|c| c.is_control() || c == '\u{FFFE}' || c == '\u{FFFF}')
    {
        Some("contains a control character (not allowed in XML 1.0 text)")
    } else {
        None
    }
}

pub(super) fn stream_header_xml(spec: &XdfStream, created_at: Option<f64>) -> String {
    let mut x = String::from("<?xml version=\"1.0\"?>\n<info>");
    let _ = write!(
        x,
        "<name>{}</name><type>{}</type><channel_count>{}</channel_count>\
         <channel_format>{}</channel_format><source_id>{}</source_id>\
         <nominal_srate>{}</nominal_srate>",
        xml_escape(&spec.name),
        xml_escape(&spec.stream_type),
        spec.channel_labels.len(),
        spec.format.name(),
        xml_escape(&spec.source_id),
        spec.nominal_srate,
    );
    if let Some(t) = created_at {
        let _ = write!(x, "<created_at>{t}</created_at>");
    }
    x.push_str("<desc><channels>");
    for label in &spec.channel_labels {
        let _ = write!(
            x,
            "<channel><label>{}</label><unit>{}</unit><type>{}</type></channel>",
            xml_escape(label),
            xml_escape(&spec.unit),
            xml_escape(&spec.stream_type)
        );
    }
    let _ = writeln!(
        x,
        "</channels><acquisition><manufacturer>oddball-io {}</manufacturer></acquisition></desc></info>",
        env!("CARGO_PKG_VERSION")
    );
    x
}

// ---------------------------------------------------------------------------------------------
// Reading headers and footers (roxmltree)
// ---------------------------------------------------------------------------------------------

/// An element as the header readers need it: its name, its own text (text and CDATA children,
/// entities decoded) and where that text starts.
#[derive(Debug, Clone, Default)]
pub(super) struct XmlNode {
    pub(super) name: String,
    pub(super) text: String,
    /// Byte offset (in the XML text) of the element's first non-blank text, else of its start.
    pub(super) text_offset: usize,
    pub(super) children: Vec<XmlNode>,
}

impl XmlNode {
    pub(super) fn child(&self, name: &str) -> Option<&XmlNode> {
        self.children.iter().find(|c| c.name == name)
    }

    pub(super) fn children_named<'a>(
        &'a self,
        name: &'a str,
    ) -> impl Iterator<Item = &'a XmlNode> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }

    pub(super) fn child_text(&self, name: &str) -> Option<&str> {
        self.child(name).map(|c| c.text.trim())
    }
}

/// Why an XML text was refused: the byte offset in the text, what was expected, what was there.
#[derive(Debug)]
pub(super) struct XmlError {
    pub(super) offset: usize,
    pub(super) expected: String,
    pub(super) found: String,
}

pub(super) fn snippet(s: &str, at: usize) -> String {
    s.get(at..)
        .unwrap_or("")
        .chars()
        .take(20)
        .collect::<String>()
}

/// The byte offset of roxmltree's 1-based (row, column in characters) position in `s`.
pub(super) fn byte_offset(s: &str, pos: roxmltree::TextPos) -> usize {
    let mut line_start = 0;
    for _ in 1..pos.row {
        match s[line_start..].find('\n') {
            Some(i) => line_start += i + 1,
            None => return s.len(),
        }
    }
    s[line_start..]
        .char_indices()
        .nth(pos.col.saturating_sub(1) as usize)
        .map_or(s.len(), |(i, _)| line_start + i)
}

/// Parses one XML document into its root element with `roxmltree` (DTDs allowed, its entity
/// limits apply; at most [`MAX_XML_DEPTH`] nested elements). A roxmltree error becomes the
/// byte offset of its position, its message, and the text found there.
pub(super) fn parse_xml(s: &str) -> Result<XmlNode, XmlError> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    let doc = roxmltree::Document::parse_with_options(s, options).map_err(|e| {
        let offset = byte_offset(s, e.pos());
        let message = e.to_string();
        let message = message
            .rsplit_once(" at ")
            .map_or(message.as_str(), |(m, _)| m);
        XmlError {
            offset,
            expected: format!("well-formed XML ({message})"),
            found: snippet(s, offset),
        }
    })?;
    convert(s, doc.root_element(), 1)
}

pub(super) fn convert(
    s: &str,
    node: roxmltree::Node<'_, '_>,
    depth: usize,
) -> Result<XmlNode, XmlError> {
    let start = node.range().start;
    if depth > MAX_XML_DEPTH {
        return Err(XmlError {
            offset: start,
            expected: format!("at most {MAX_XML_DEPTH} nested elements"),
            found: snippet(s, start),
        });
    }
    let mut out = XmlNode {
        name: node.tag_name().name().to_string(),
        text: String::new(),
        text_offset: start,
        children: Vec::new(),
    };
    for child in node.children() {
        if child.is_element() {
            out.children.push(convert(s, child, depth + 1)?);
        } else if let Some(text) = child.text().filter(|_| child.is_text()) {
            if out.text.trim().is_empty() {
                let range = child.range();
                if let Some(k) = s[range.clone()].find(|c: char| !c.is_whitespace()) {
                    out.text_offset = range.start + k;
                }
            }
            out.text.push_str(text);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_reader() {
        let x = "\u{feff}<?xml version=\"1.0\"?>\n<!-- c --><info a='1' b = \"x>y\"><name>A &amp; B &#x263A;</name>\
                 <desc/><n><![CDATA[<raw>]]></n><channels><channel><label> Cz </label></channel>\
                 <channel><label>Pz</label></channel></channels></info>\n";
        let r = parse_xml(x).unwrap();
        assert_eq!(r.name, "info");
        assert_eq!(r.child_text("name"), Some("A & B \u{263A}"));
        assert_eq!(r.child_text("n"), Some("<raw>"));
        assert!(r.child("desc").unwrap().children.is_empty());
        let labels: Vec<_> = r
            .child("channels")
            .unwrap()
            .children_named("channel")
            .map(|c| c.child_text("label").unwrap())
            .collect();
        assert_eq!(labels, ["Cz", "Pz"]);
        let cz = &r.child("channels").unwrap().children[0].children[0];
        assert_eq!(&x[cz.text_offset..cz.text_offset + 2], "Cz");
        for bad in [
            "<a><b></a>",
            "<a>",
            "x<a/>",
            "<a/><b/>",
            "<a>&bogus;</a>",
            "<a x=1/>",
            "<a></a>z",
            "",
            "<",
            "</a>",
            "<a><!--</a>",
        ] {
            assert!(parse_xml(bad).is_err(), "{bad:?}");
        }
        let deep = "<a>".repeat(100);
        assert!(parse_xml(&deep).is_err());
    }
}
#[cfg(test)]
mod error_offsets {
    /// roxmltree's (row, column) positions become byte offsets pointing at the fault.
    #[test]
    fn errors_point_at_the_byte_at_fault() {
        for (bad, offset, found) in [
            ("<info><name>x</info>", 13, "</info>"),
            ("<info>\n  <a>&bogus;</a></info>", 12, "&bogus;"),
            ("<info>\n  é<a x=1/></info>", 16, "1/>"),
            ("<a></a>z", 7, "z"),
            ("<a/><b/>", 4, "<b/>"),
            ("", 0, ""),
        ] {
            let e = super::parse_xml(bad).unwrap_err();
            assert_eq!(e.offset, offset, "{bad:?}: {e:?}");
            assert!(e.found.starts_with(found), "{bad:?}: {e:?}");
            assert!(e.expected.starts_with("well-formed XML ("), "{e:?}");
        }
        let deep = "<a>".repeat(100) + &"</a>".repeat(100);
        let e = super::parse_xml(&deep).unwrap_err();
        assert_eq!(
            (e.offset, e.expected.as_str()),
            (192, "at most 64 nested elements")
        );
    }
}
