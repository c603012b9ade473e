//! A tiny, allocation-free XML scanner for the telegrams of this crate.
//!
//! It is not a general XML parser: it understands elements, attributes with
//! single or double quotes, text, comments, processing instructions,
//! `<!DOCTYPE ...>` and CDATA sections, checks that end tags match start tags
//! (up to [`MAX_DEPTH`] levels) and never decodes entities (the telegrams
//! carry numbers). Names are returned as raw byte slices; compare them with
//! [`name_eq`], which ignores ASCII case as KUKA RSI does.
//!
//! Every malformation is a [`LinkError::Malformed`] with
//! [`Protocol::Xml`]; the scanner never panics whatever the input.

use crate::error::{LinkError, Protocol};

/// Maximum element nesting depth accepted.
pub const MAX_DEPTH: usize = 16;

const fn err(reason: &'static str) -> LinkError {
    LinkError::malformed(Protocol::Xml, reason)
}

/// True if `name` equals `expected` ignoring ASCII case.
pub fn name_eq(name: &[u8], expected: &str) -> bool {
    name.eq_ignore_ascii_case(expected.as_bytes())
}

/// One syntactic event of the document.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XmlEvent<'a> {
    /// A start tag (or an empty-element tag when `self_closing`).
    Start {
        /// Element name.
        name: &'a [u8],
        /// The element's attributes, parsed lazily.
        attrs: Attributes<'a>,
        /// True for `<name .../>`.
        self_closing: bool,
    },
    /// An end tag `</name>`.
    End {
        /// Element name.
        name: &'a [u8],
    },
    /// Non-blank character data (trimmed of surrounding whitespace).
    Text(&'a [u8]),
}

/// Lazily parsed attribute list of a start tag; iterate it to get
/// `(name, value)` pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Attributes<'a> {
    raw: &'a [u8],
    pos: usize,
}

impl<'a> Attributes<'a> {
    /// Value of the first attribute named `name` (ASCII case-insensitive).
    pub fn get(&self, name: &str) -> Result<Option<&'a [u8]>, LinkError> {
        for a in *self {
            let (n, v) = a?;
            if name_eq(n, name) {
                return Ok(Some(v));
            }
        }
        Ok(None)
    }
}

fn is_name_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.' | b':')
}

impl<'a> Iterator for Attributes<'a> {
    type Item = Result<(&'a [u8], &'a [u8]), LinkError>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = self.raw;
        let mut i = self.pos;
        while i < r.len() && r[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= r.len() {
            self.pos = r.len();
            return None;
        }
        // Any error ends the iteration after being reported once.
        self.pos = r.len();
        let start = i;
        while i < r.len() && is_name_byte(r[i]) {
            i += 1;
        }
        if i == start {
            return Some(Err(err("bad character in attribute list")));
        }
        let name = &r[start..i];
        while i < r.len() && r[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= r.len() || r[i] != b'=' {
            return Some(Err(err("attribute without '='")));
        }
        i += 1;
        while i < r.len() && r[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= r.len() || !matches!(r[i], b'"' | b'\'') {
            return Some(Err(err("attribute value not quoted")));
        }
        let quote = r[i];
        i += 1;
        let vstart = i;
        while i < r.len() && r[i] != quote {
            if r[i] == b'<' {
                return Some(Err(err("'<' in attribute value")));
            }
            i += 1;
        }
        if i >= r.len() {
            return Some(Err(err("unterminated attribute value")));
        }
        let value = &r[vstart..i];
        i += 1;
        if i < r.len() && !r[i].is_ascii_whitespace() {
            return Some(Err(err("attributes not separated by whitespace")));
        }
        self.pos = i;
        Some(Ok((name, value)))
    }
}

/// Pull scanner over a byte slice.
#[derive(Debug, Clone)]
pub struct XmlScanner<'a> {
    buf: &'a [u8],
    pos: usize,
    stack: [&'a [u8]; MAX_DEPTH],
    depth: usize,
    seen_root: bool,
}

fn find(hay: &[u8], from: usize, needle: &[u8]) -> Option<usize> {
    if from > hay.len() {
        return None;
    }
    hay[from..]
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|p| p + from)
}

impl<'a> XmlScanner<'a> {
    /// Starts scanning `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        XmlScanner {
            buf,
            pos: 0,
            stack: [&[]; MAX_DEPTH],
            depth: 0,
            seen_root: false,
        }
    }

    /// Current element nesting depth (1 inside the root element).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Next event, `Ok(None)` at the end of a well-formed document.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<Option<XmlEvent<'a>>, LinkError> {
        let b = self.buf;
        loop {
            if self.pos >= b.len() {
                if self.depth != 0 {
                    return Err(err("unclosed element at end of input"));
                }
                if !self.seen_root {
                    return Err(err("no element in document"));
                }
                return Ok(None);
            }
            if b[self.pos] != b'<' {
                let start = self.pos;
                let end = find(b, start, b"<").unwrap_or(b.len());
                self.pos = end;
                let text = crate::udp::trim(&b[start..end]);
                if text.is_empty() {
                    continue;
                }
                if self.depth == 0 {
                    return Err(err("text outside the root element"));
                }
                return Ok(Some(XmlEvent::Text(text)));
            }
            let rest = &b[self.pos..];
            if rest.starts_with(b"<?") {
                self.pos = find(b, self.pos + 2, b"?>").ok_or(err("unterminated <?...?>"))? + 2;
                continue;
            }
            if rest.starts_with(b"<!--") {
                self.pos = find(b, self.pos + 4, b"-->").ok_or(err("unterminated comment"))? + 3;
                continue;
            }
            if rest.starts_with(b"<![CDATA[") {
                let start = self.pos + 9;
                let end = find(b, start, b"]]>").ok_or(err("unterminated CDATA"))?;
                self.pos = end + 3;
                if self.depth == 0 {
                    return Err(err("CDATA outside the root element"));
                }
                return Ok(Some(XmlEvent::Text(&b[start..end])));
            }
            if rest.starts_with(b"<!") {
                self.pos = find(b, self.pos + 2, b">").ok_or(err("unterminated <!...>"))? + 1;
                continue;
            }
            return self.tag().map(Some);
        }
    }

    fn tag(&mut self) -> Result<XmlEvent<'a>, LinkError> {
        let b = self.buf;
        let mut i = self.pos + 1;
        let closing = i < b.len() && b[i] == b'/';
        if closing {
            i += 1;
        }
        let nstart = i;
        while i < b.len() && is_name_byte(b[i]) {
            i += 1;
        }
        if i == nstart {
            return Err(err("tag without a name"));
        }
        let name = &b[nstart..i];
        // Find the closing '>' outside quotes.
        let astart = i;
        let mut quote = 0u8;
        while i < b.len() {
            let c = b[i];
            if quote != 0 {
                if c == quote {
                    quote = 0;
                }
            } else if c == b'"' || c == b'\'' {
                quote = c;
            } else if c == b'>' {
                break;
            } else if c == b'<' {
                return Err(err("'<' inside a tag"));
            }
            i += 1;
        }
        if i >= b.len() {
            return Err(err("unterminated tag"));
        }
        self.pos = i + 1;
        let mut inner = &b[astart..i];
        if closing {
            if !crate::udp::trim(inner).is_empty() {
                return Err(err("garbage in end tag"));
            }
            if self.depth == 0 {
                return Err(err("end tag without start tag"));
            }
            self.depth -= 1;
            if self.stack[self.depth] != name {
                return Err(err("end tag does not match start tag"));
            }
            return Ok(XmlEvent::End { name });
        }
        let self_closing = inner.last() == Some(&b'/');
        if self_closing {
            inner = &inner[..inner.len() - 1];
        }
        if !inner.is_empty() && !inner[0].is_ascii_whitespace() {
            return Err(err("bad character after element name"));
        }
        if self.depth == 0 && self.seen_root {
            return Err(err("more than one root element"));
        }
        self.seen_root = true;
        if !self_closing {
            if self.depth >= MAX_DEPTH {
                return Err(err("elements nested too deeply"));
            }
            self.stack[self.depth] = name;
            self.depth += 1;
        }
        Ok(XmlEvent::Start {
            name,
            attrs: Attributes { raw: inner, pos: 0 },
            self_closing,
        })
    }
}
