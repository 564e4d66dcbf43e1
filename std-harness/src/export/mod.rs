//! Strands out (`hairsim_files::export`, re-exported whole: the writers, the text readers,
//! [`Format`], [`ExportError`]), plus [`OutDir`]: everything `hairsim run --out DIR` writes,
//! pictures included.

mod outdir;

pub use hairsim_files::export::*;
pub use outdir::{OutDir, OutOptions};
