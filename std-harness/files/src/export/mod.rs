//! Strands out: OBJ and PLY polylines, Cem Yuksel's `.hair`, USD ASCII `BasisCurves` and
//! TressFX `.tfx`, plus text readers (OBJ, PLY, USDA) just sufficient to read our own files back.
//!
//! Writers take any slice of polylines (`&[Vec<Vec3>]`, `&[&[Vec3]]`, …), root first. Text
//! formats print each coordinate with Rust's shortest round-trip formatting, so reading a file
//! back gives the same `f32` bits, exactly as the binary formats do. Writers refuse non-finite
//! coordinates and strands with fewer than two points (no reader here keeps those).

mod hair;
mod obj;
mod ply;
mod seeds;
mod tfx;
mod usda;

use std::fmt;
use std::io::{self, Write};
use std::path::Path;

use hairsim_core::Vec3;

pub use hair::write_hair;
pub use obj::{read_obj, write_obj};
pub use ply::{read_ply, write_ply};
pub use seeds::{fuzz_seeds, write_fuzz_seeds};
pub use tfx::write_tfx;
pub use usda::{read_usda, write_usda};

/// Default strand width written where a format has one (`.hair` thickness, USD `widths`):
/// a hair's diameter, 80 µm.
pub const DEFAULT_WIDTH: f32 = 8.0e-5;

/// Why strands could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Writing failed.
    #[error("write failed: {0}")]
    Io(#[from] io::Error),
    /// A coordinate is NaN or infinite.
    #[error("strand {strand}, vertex {vertex}: non-finite coordinate")]
    NonFinite {
        /// Strand index.
        strand: usize,
        /// Vertex index in the strand.
        vertex: usize,
    },
    /// A strand has fewer than two points.
    #[error("strand {strand} has {points} point(s); at least 2 are needed")]
    TooShort {
        /// Strand index.
        strand: usize,
        /// Its number of points.
        points: usize,
    },
    /// A strand has more points than the format can hold.
    #[error("strand {strand} has {points} points; {format} holds at most {max}")]
    TooLong {
        /// Strand index.
        strand: usize,
        /// Its number of points.
        points: usize,
        /// The format.
        format: &'static str,
        /// Its limit.
        max: usize,
    },
    /// More strands or points than the format's 32-bit counts hold.
    #[error("{what} {count} exceeds the format's 32-bit count")]
    TooMany {
        /// What was counted.
        what: &'static str,
        /// How many.
        count: usize,
    },
    /// TressFX needs the same vertex count on every strand.
    #[error("strand {strand} has {points} points but strand 0 has {first}; TressFX needs equal counts (resample first)")]
    UnequalStrands {
        /// Strand index.
        strand: usize,
        /// Its number of points.
        points: usize,
        /// Strand 0's.
        first: usize,
    },
    /// A strand width that is negative or not finite.
    #[error("bad strand width {0}: must be finite and >= 0")]
    BadWidth(f32),
    /// The path's extension names no format.
    #[error("{0}: unknown extension (expected .obj, .ply, .hair, .usda or .tfx)")]
    UnknownExtension(String),
    /// A picture could not be drawn or encoded (`hairsim::picture::PictureError`, from
    /// `hairsim::export::OutDir`: the pictures are the harness's, not this crate's).
    #[error("picture: {0}")]
    Picture(Box<dyn std::error::Error + Send + Sync>),
}

/// Why a text file (OBJ, PLY, USDA) could not be read back.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("{format} line {line}: {message}")]
pub struct TextReadError {
    /// "OBJ", "PLY" or "USDA".
    pub format: &'static str,
    /// 1-based line number (0 when the problem is with the file as a whole).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl TextReadError {
    pub(crate) fn new(format: &'static str, line: usize, message: impl fmt::Display) -> Self {
        TextReadError {
            format,
            line,
            message: message.to_string(),
        }
    }
}

/// A file format strands can be written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// Wavefront OBJ: `v` lines strand by strand, root to tip, one `l` line per strand.
    Obj,
    /// Stanford PLY, ASCII: vertex and edge elements.
    Ply,
    /// Cem Yuksel's binary HAIR.
    Hair,
    /// USD ASCII with one linear `BasisCurves` prim.
    Usda,
    /// AMD TressFX 4.x (equal vertex counts per strand).
    Tfx,
}

impl Format {
    /// Every format, in a stable order.
    pub const ALL: [Format; 5] = [
        Format::Obj,
        Format::Ply,
        Format::Hair,
        Format::Usda,
        Format::Tfx,
    ];

    /// The file extension, without the dot.
    #[must_use]
    pub fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Hair => "hair",
            Format::Usda => "usda",
            Format::Tfx => "tfx",
        }
    }

    /// The format a path's extension names, if any (case-insensitive).
    #[must_use]
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Format::ALL.into_iter().find(|f| f.extension() == ext)
    }

    /// Writes `strands` in this format. `width` is the strand diameter where the format has one.
    ///
    /// # Errors
    /// See [`ExportError`].
    pub fn write<W: Write, S: AsRef<[Vec3]>>(
        self,
        out: W,
        strands: &[S],
        width: f32,
    ) -> Result<(), ExportError> {
        match self {
            Format::Obj => write_obj(out, strands),
            Format::Ply => write_ply(out, strands),
            Format::Hair => write_hair(out, strands, width),
            Format::Usda => write_usda(out, strands, width),
            Format::Tfx => write_tfx(out, strands),
        }
    }
}

impl std::str::FromStr for Format {
    type Err = String;

    /// An extension without the dot (`obj`, `ply`, `hair`, `usda`, `tfx`), any case, for
    /// command-line options such as `--frames obj,usda`.
    fn from_str(name: &str) -> Result<Format, String> {
        let name = name.trim_start_matches('.').to_ascii_lowercase();
        Format::ALL
            .into_iter()
            .find(|f| f.extension() == name)
            .ok_or_else(|| format!("unknown format {name:?} (obj, ply, hair, usda or tfx)"))
    }
}

/// Writes `strands` to `path` in the format its extension names, with [`DEFAULT_WIDTH`].
///
/// # Errors
/// An unknown extension, I/O, or what the writer refuses.
pub fn save<S: AsRef<[Vec3]>>(path: &Path, strands: &[S]) -> Result<(), ExportError> {
    let format = Format::from_path(path)
        .ok_or_else(|| ExportError::UnknownExtension(path.display().to_string()))?;
    let file = std::fs::File::create(path)?;
    format.write(file, strands, DEFAULT_WIDTH)
}

/// Checks what every writer needs: ≥ 2 points per strand and finite coordinates.
pub(crate) fn check_strands<S: AsRef<[Vec3]>>(strands: &[S]) -> Result<(), ExportError> {
    for (strand, s) in strands.iter().enumerate() {
        let s = s.as_ref();
        if s.len() < 2 {
            return Err(ExportError::TooShort {
                strand,
                points: s.len(),
            });
        }
        if let Some(vertex) = s.iter().position(|p| !p.is_finite()) {
            return Err(ExportError::NonFinite { strand, vertex });
        }
    }
    Ok(())
}

/// A coordinate in shortest round-trip form (`{:?}` on `f32`: `1.0`, `-0.25`, `1e-7`), which
/// every OBJ/PLY/USD parser reads and which parses back to the same bits.
pub(crate) struct Num(pub f32);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.0)
    }
}

/// Parses a float token, refusing non-finite values.
pub(crate) fn parse_coordinate(
    format: &'static str,
    line: usize,
    token: Option<&str>,
) -> Result<f32, TextReadError> {
    let token = token.ok_or_else(|| TextReadError::new(format, line, "missing coordinate"))?;
    let value: f32 = token
        .parse()
        .map_err(|_| TextReadError::new(format, line, format!("bad number {token:?}")))?;
    if !value.is_finite() {
        return Err(TextReadError::new(
            format,
            line,
            format!("non-finite coordinate {token:?}"),
        ));
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_parse_from_their_names() {
        for f in Format::ALL {
            assert_eq!(f.extension().parse::<Format>(), Ok(f));
            assert_eq!(
                Format::from_path(Path::new(&format!("a/b.{}", f.extension()))),
                Some(f)
            );
        }
        assert_eq!(".USDA".parse::<Format>(), Ok(Format::Usda));
        assert!("abc".parse::<Format>().is_err());
    }
}

#[cfg(test)]
pub(crate) mod test_strands {
    use hairsim_core::Vec3;

    /// Strands of unequal lengths with awkward values: negative zero, tiny and huge magnitudes,
    /// values with no short decimal form.
    pub fn awkward() -> Vec<Vec<Vec3>> {
        vec![
            vec![
                Vec3::new(0.0, -0.0, 1.0),
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1.0e-7, -3.5e-12, 1.0e30),
            ],
            vec![
                Vec3::new(1.0 / 3.0, 2.0 / 7.0, -5.0 / 9.0),
                Vec3::splat(f32::MIN_POSITIVE),
            ],
            (0..40)
                .map(|i| Vec3::new((i as f32 * 0.37).sin(), -0.01 * i as f32, 1.5))
                .collect(),
        ]
    }

    /// Strands all of 8 points.
    pub fn equal() -> Vec<Vec<Vec3>> {
        (0..5)
            .map(|s| {
                (0..8)
                    .map(|i| Vec3::new(s as f32 * 0.01, -0.02 * i as f32, (s * i) as f32 * 1e-3))
                    .collect()
            })
            .collect()
    }

    /// Bitwise equality, so `-0.0` vs `0.0` and last-bit differences are caught.
    pub fn assert_same_bits(a: &[Vec<Vec3>], b: &[Vec<Vec3>]) {
        assert_eq!(a.len(), b.len(), "strand count");
        for (s, (x, y)) in a.iter().zip(b).enumerate() {
            assert_eq!(x.len(), y.len(), "strand {s} length");
            for (v, (p, q)) in x.iter().zip(y).enumerate() {
                for (c, (u, w)) in p.to_array().iter().zip(q.to_array()).enumerate() {
                    assert_eq!(
                        u.to_bits(),
                        w.to_bits(),
                        "strand {s} vertex {v} axis {c}: {u} vs {w}"
                    );
                }
            }
        }
    }
}
