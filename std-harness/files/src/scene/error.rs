//! Scene errors: `FILE:LINE: field: what is wrong, and what is allowed`.

use std::fmt;

/// A scene error placed in its file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// The scene file (or `builtin:NAME`, or `RECORDING#scene`).
    pub file: String,
    /// 1-based line of the field, 0 when the error is not about a line (unreadable file).
    pub line: usize,
    /// Dotted path of the field (`material.radius`, `strands[2].points`), empty for the file.
    pub field: String,
    /// What is wrong, and what is allowed.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.field.is_empty()) {
            (0, true) => write!(f, "{}: {}", self.file, self.message),
            (0, false) => write!(f, "{}: {}: {}", self.file, self.field, self.message),
            (line, true) => write!(f, "{}:{}: {}", self.file, line, self.message),
            (line, false) => write!(
                f,
                "{}:{}: {}: {}",
                self.file, line, self.field, self.message
            ),
        }
    }
}

impl std::error::Error for SceneError {}

/// A field that failed a check, before it is placed at a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldError {
    /// Dotted path of the field.
    pub field: String,
    /// What is wrong, and what is allowed.
    pub message: String,
}

impl FieldError {
    /// An error about `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> FieldError {
        FieldError {
            field: field.into(),
            message: message.into(),
        }
    }

    /// Places the error in a scene that has no text (a built-in scene).
    #[must_use]
    pub fn in_builtin(&self, name: &str) -> SceneError {
        SceneError {
            file: format!("builtin:{name}"),
            line: 0,
            field: self.field.clone(),
            message: self.message.clone(),
        }
    }
}

impl fmt::Display for FieldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

impl std::error::Error for FieldError {}

/// 1-based line of byte `offset` in `text`.
#[must_use]
pub fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A TOML syntax error (the document does not parse at all).
#[must_use]
pub fn from_toml(file: &str, text: &str, error: &toml::de::Error) -> SceneError {
    SceneError {
        file: file.to_string(),
        line: error
            .span()
            .map_or(1, |span| line_of_offset(text, span.start)),
        field: String::new(),
        message: format!("not valid TOML: {}", one_line(error.message())),
    }
}

/// Serde's and toml's messages on one line.
#[must_use]
pub fn one_line(message: &str) -> String {
    message.trim().replace('\n', "; ")
}
