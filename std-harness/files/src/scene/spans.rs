//! Where each field of a scene file sits: dotted paths (`strands[2].points`) with the byte
//! spans of their keys and values, so that serde's errors (which carry a span) get a field
//! name, and validation errors (which carry a field name) get a line.

use std::ops::Range;

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::error::{line_of_offset, one_line, SceneError};

/// One field of the document.
#[derive(Clone, Debug)]
struct Entry {
    path: String,
    key: Option<Range<usize>>,
    value: Range<usize>,
}

/// Every field of a parsed document, parents before children.
#[derive(Clone, Debug, Default)]
pub struct SpanIndex {
    entries: Vec<Entry>,
}

impl SpanIndex {
    /// Indexes `text`, or gives the TOML syntax error.
    pub fn parse(text: &str) -> Result<SpanIndex, toml::de::Error> {
        let document = DeTable::parse(text)?;
        let mut index = SpanIndex::default();
        index.table("", document.get_ref());
        Ok(index)
    }

    fn table(&mut self, prefix: &str, table: &DeTable<'_>) {
        for (key, value) in table.iter() {
            let path = if prefix.is_empty() {
                key.get_ref().to_string()
            } else {
                format!("{prefix}.{}", key.get_ref())
            };
            self.value(path, Some(key.span()), value);
        }
    }

    fn value(&mut self, path: String, key: Option<Range<usize>>, value: &Spanned<DeValue<'_>>) {
        self.entries.push(Entry {
            path: path.clone(),
            key,
            value: value.span(),
        });
        match value.get_ref() {
            DeValue::Table(table) => self.table(&path, table),
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    self.value(format!("{path}[{i}]"), None, item);
                }
            }
            _ => {}
        }
    }

    /// 1-based line of `field`, or of its nearest ancestor present in the document (a missing
    /// field is reported at its table), or 1.
    #[must_use]
    pub fn line_of(&self, field: &str, text: &str) -> usize {
        let mut path = field;
        loop {
            if let Some(entry) = self.entries.iter().find(|e| e.path == path) {
                let start = entry.key.as_ref().map_or(entry.value.start, |k| k.start);
                return line_of_offset(text, start);
            }
            match parent(path) {
                Some(p) => path = p,
                None => return 1,
            }
        }
    }

    /// The deepest field whose key or value holds byte `offset`.
    fn field_at(&self, offset: usize) -> Option<&Entry> {
        let holds = |r: &Range<usize>| r.start <= offset && offset < r.end.max(r.start + 1);
        self.entries
            .iter()
            .filter(|e| holds(&e.value) || e.key.as_ref().is_some_and(holds))
            .max_by_key(|e| (e.path.len(), usize::MAX - e.value.len()))
    }

    /// Places a deserialisation error (unknown field, wrong type, missing field) at its field.
    #[must_use]
    pub fn serde_error(&self, file: &str, text: &str, error: &toml::de::Error) -> SceneError {
        let message = one_line(error.message());
        let span = error.span();
        let missing = message
            .strip_prefix("missing field `")
            .and_then(|rest| rest.split('`').next());
        let entry = match (&span, missing) {
            // A missing field is reported with its table's span (none for the whole document).
            (Some(s), Some(_)) => self
                .entries
                .iter()
                .filter(|e| e.value == *s)
                .max_by_key(|e| e.path.len()),
            (Some(s), None) => self.field_at(s.start),
            (None, _) => None,
        };
        let mut field = entry.map(|e| e.path.clone()).unwrap_or_default();
        if let Some(name) = missing {
            field = if field.is_empty() {
                name.to_string()
            } else {
                format!("{field}.{name}")
            };
        }
        let line = span.map_or(1, |s| line_of_offset(text, s.start));
        SceneError {
            file: file.to_string(),
            line,
            field,
            message: explain(&message),
        }
    }
}

/// The parent of a dotted path (`a.b[2].c` → `a.b[2]` → `a.b` → `a`).
fn parent(path: &str) -> Option<&str> {
    let cut = path.rfind(['.', '['])?;
    Some(&path[..cut])
}

/// Serde's wording, with what is allowed spelled out where serde leaves it implicit.
fn explain(message: &str) -> String {
    if message.starts_with("missing field") {
        format!("{message}: this field is required")
    } else {
        message.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_and_lines() {
        let text = "a = 1\n[t]\nb = [1, 2]\n[[s]]\nc = 3\n[[s]]\nc = 4\n";
        let index = SpanIndex::parse(text).unwrap();
        assert_eq!(index.line_of("a", text), 1);
        assert_eq!(index.line_of("t.b", text), 3);
        assert_eq!(index.line_of("s[1].c", text), 7);
        // A missing field is placed at its table's header.
        assert_eq!(index.line_of("s[1].missing", text), 6);
        assert_eq!(index.line_of("nowhere", text), 1);
        assert_eq!(parent("a.b[2].c"), Some("a.b[2]"));
        assert_eq!(parent("a.b[2]"), Some("a.b"));
    }
}
