//! Pictures.
/// Picture error.
#[derive(Debug, thiserror::Error)]
#[error("picture")]
pub struct PictureError;
