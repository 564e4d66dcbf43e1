//! `hairsim replay FILE`.

use std::path::Path;

use anyhow::Result;

/// Replays a recording; the run's summary when every hash matched.
pub fn replay(file: &Path, threads: usize, json: bool) -> Result<String> {
    let summary = crate::run::replay(file, threads)?;
    Ok(if json {
        summary.to_json()
    } else {
        format!(
            "replay ok: every recorded state hash matched\n{}",
            summary.to_text()
        )
    })
}
