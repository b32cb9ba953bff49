//! The model text with its file label: byte offsets to 1-based line:column, and errors.

use crate::model::{ModelError, SrcPos};

/// The text being read and where it came from.
pub(crate) struct Source<'t> {
    /// Label of the text in messages (usually its path).
    pub file: String,
    /// The whole model text, as read (a byte-order mark included).
    pub text: &'t str,
    line_starts: Vec<usize>,
}

impl<'t> Source<'t> {
    /// Index the line starts of `text`, labelled `file` in messages.
    pub fn new(text: &'t str, file: &str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Source { file: file.to_string(), text, line_starts }
    }

    /// Line and column (in characters, both 1-based) of byte offset `off`. A UTF-8 byte
    /// order mark is not a column: editors do not show it.
    pub fn pos(&self, off: usize) -> SrcPos {
        let off = off.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= off).max(1);
        let bom = if line == 1 && self.text.starts_with('\u{feff}') { '\u{feff}'.len_utf8() } else { 0 };
        let start = self.line_starts[line - 1] + bom;
        let off = off.max(start);
        let col = self.text.get(start..off).map_or(off - start, |s| s.chars().count()) + 1;
        SrcPos { line, col }
    }

    /// Byte offset of `s` in the text when `s` borrows from it.
    pub fn offset_of(&self, s: &str) -> Option<usize> {
        let base = self.text.as_ptr() as usize;
        let p = s.as_ptr() as usize;
        (p >= base && p + s.len() <= base + self.text.len()).then(|| p - base)
    }

    /// A located error.
    pub fn error(&self, pos: SrcPos, element: &str, name: &str, msg: impl Into<String>) -> ModelError {
        ModelError {
            file: self.file.clone(),
            pos,
            element: element.to_string(),
            name: name.to_string(),
            msg: msg.into(),
        }
    }
}
