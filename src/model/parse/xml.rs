//! XML reading into a small element tree that remembers where everything was written.

use super::source::Source;
use crate::model::{ModelError, SrcPos};
use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

/// One attribute: name, unescaped value, and positions.
#[derive(Debug)]
pub(crate) struct XAttr {
    /// Attribute name as written (no namespace handling).
    pub name: String,
    /// Value with entities replaced and white space normalized as XML requires (a line end
    /// or tab becomes a space).
    pub value: String,
    /// Position of the attribute name.
    pub pos: SrcPos,
    /// Byte offset of the first character of the raw value (after the quote).
    pub value_off: Option<usize>,
}

/// One element with its attributes and child elements (text and comments dropped).
#[derive(Debug)]
pub(crate) struct XElem {
    /// Element name as written (`body`, `joint`, ...).
    pub tag: String,
    /// Position of the element's `<`.
    pub pos: SrcPos,
    /// Attributes in written order.
    pub attrs: Vec<XAttr>,
    /// Child elements in written order.
    pub children: Vec<XElem>,
}

impl XElem {
    /// The value of attribute `name`, if present.
    pub fn attr(&self, name: &str) -> Option<&XAttr> {
        self.attrs.iter().find(|a| a.name == name)
    }
    /// The `name` attribute, or the tag for unnamed elements (for messages).
    pub fn label(&self) -> &str {
        self.attr("name").map_or(&self.tag, |a| &a.value)
    }
}

/// Deepest element nesting accepted (the format needs 3; this bounds recursion).
const MAX_DEPTH: usize = 32;

/// Parse the whole text; returns the single root element.
pub(crate) fn read(src: &Source) -> Result<XElem, ModelError> {
    // quick-xml skips one leading UTF-8 byte order mark and counts its offsets from after
    // it: `base` turns them into offsets of the whole text. (Stripping the mark here
    // instead would let quick-xml skip a second one, uncounted.)
    let base = if src.text.starts_with('\u{feff}') { '\u{feff}'.len_utf8() } else { 0 };
    let mut reader = Reader::from_str(src.text);
    let mut stack: Vec<XElem> = Vec::new();
    let mut root: Option<XElem> = None;
    loop {
        let before = base + usize::try_from(reader.buffer_position()).unwrap_or(0);
        let ev = match reader.read_event() {
            Ok(ev) => ev,
            Err(e) => {
                let at = base + usize::try_from(reader.error_position()).unwrap_or(0);
                return Err(src.error(src.pos(at), "xml", "document", format!("malformed XML: {e}")));
            }
        };
        match ev {
            Event::Start(e) => {
                let el = element(src, &e, before)?;
                if stack.len() >= MAX_DEPTH {
                    return Err(src.error(el.pos, &el.tag, el.label(), "elements nested too deeply"));
                }
                stack.push(el);
            }
            Event::Empty(e) => {
                let el = element(src, &e, before)?;
                attach(src, &mut stack, &mut root, el)?;
            }
            Event::End(_) => {
                if let Some(el) = stack.pop() {
                    attach(src, &mut stack, &mut root, el)?;
                }
            }
            Event::Text(t) => {
                if !t.trim().is_empty() {
                    return Err(unexpected_text(src, &stack, before));
                }
            }
            Event::CData(_) | Event::GeneralRef(_) => {
                return Err(unexpected_text(src, &stack, before));
            }
            Event::Comment(_) | Event::Decl(_) | Event::PI(_) | Event::DocType(_) => {}
            Event::Eof => break,
        }
    }
    if let Some(open) = stack.last() {
        return Err(src.error(open.pos, &open.tag, open.label(), "element is not closed"));
    }
    root.ok_or_else(|| src.error(SrcPos { line: 1, col: 1 }, "multibody", "multibody", "no <multibody> root element"))
}

fn unexpected_text(src: &Source, stack: &[XElem], off: usize) -> ModelError {
    let (tag, name) = stack.last().map_or(("multibody", "multibody"), |e| (&e.tag, e.label()));
    let mut at = off;
    // Point at the first non-blank character of the text.
    if let Some(rest) = src.text.get(off..) {
        at += rest.len() - rest.trim_start().len();
    }
    src.error(src.pos(at), tag, name, "unexpected text")
}

fn attach(src: &Source, stack: &mut [XElem], root: &mut Option<XElem>, el: XElem) -> Result<(), ModelError> {
    if let Some(parent) = stack.last_mut() {
        parent.children.push(el);
    } else if root.is_some() {
        return Err(src.error(el.pos, &el.tag, el.label(), "more than one root element"));
    } else {
        *root = Some(el);
    }
    Ok(())
}

fn element(src: &Source, e: &BytesStart, before: usize) -> Result<XElem, ModelError> {
    let tag = e.name().0.to_string();
    // The name borrows from the text; the `<` is just before it.
    let lt = src.offset_of(e.name().0).map_or(before, |o| o.saturating_sub(1));
    let pos = src.pos(lt);
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| src.error(pos, &tag, &tag, format!("bad attribute syntax: {err}")))?;
        let name = a.key.0.to_string();
        let apos = src.offset_of(a.key.0).map_or(pos, |o| src.pos(o));
        let value = a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map_err(|err| src.error(apos, &tag, &tag, format!("bad attribute '{name}': {err}")))?
            .into_owned();
        attrs.push(XAttr { name, value, pos: apos, value_off: src.offset_of(&a.value) });
    }
    Ok(XElem { tag, pos, attrs, children: Vec::new() })
}
