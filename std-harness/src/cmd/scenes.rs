//! `hairsim scenes`.

use crate::builtin::BUILTINS;

/// One line per built-in scene, starting with its name.
#[must_use]
pub fn list() -> String {
    BUILTINS
        .iter()
        .map(|b| format!("{:<12} {}", b.name, b.about))
        .collect::<Vec<_>>()
        .join("\n")
}
