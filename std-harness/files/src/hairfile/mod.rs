//! Hair files in: Cem Yuksel's `.hair` and AMD TressFX 4.x `.tfx`.
//!
//! Both readers take the whole file as `&[u8]` (so they can be fuzzed) and return a [`HairModel`]:
//! plain polylines, root first, in hairsim's frame (Y up) after an explicit scale. Every strand is
//! a *leader*: the simulator holds nodes 0 and 1 of each (its own pinning rule), so the files'
//! own pinning data (TressFX `w = 0` inverse masses) is read past, not trusted.
//!
//! Safety against forged files: every count and offset in a header is checked, in `u64`
//! arithmetic, against the length of the file *before* anything is allocated, so the memory a
//! read takes is bounded by a small multiple of the file's size whatever its header says.

mod resample;
mod tfx;
mod yuksel;

use std::path::Path;

use hairsim_core::Vec3;

pub use resample::{polyline_length, resample_polyline};
pub use tfx::{read_tfx, TFX_HEADER_BYTES};
pub use yuksel::{read_hair, HAIR_HEADER_BYTES};

/// The bits of a HAIR header's array field.
pub mod yuksel_bits {
    pub use super::yuksel::{
        HAS_COLOURS, HAS_POINTS, HAS_SEGMENTS, HAS_THICKNESS, HAS_TRANSPARENCY,
    };
}

/// The axis that points up in a file. hairsim's world is Y-up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// The file is Y-up already (TressFX, most game engines).
    #[default]
    Y,
    /// The file is Z-up (Cem Yuksel's models, Blender, 3ds Max): `(x, y, z) → (x, z, −y)`,
    /// a rotation of −90° about X, which keeps the coordinate system right-handed.
    Z,
}

impl UpAxis {
    /// `p` (in the file's frame) in hairsim's Y-up frame.
    #[must_use]
    pub fn to_y_up(self, p: Vec3) -> Vec3 {
        match self {
            UpAxis::Y => p,
            UpAxis::Z => Vec3::new(p.x, p.z, -p.y),
        }
    }
}

/// How to turn a file's strands into hairsim leader strands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadOptions {
    /// Multiplies every coordinate (after the up-axis change): e.g. `0.01` for centimetres → m.
    pub scale: f32,
    /// The file's up axis.
    pub up_axis: UpAxis,
    /// Resample every strand to this many nodes, evenly spaced along its arc length
    /// (`None`: keep the file's vertices). Must be ≥ 2.
    pub nodes: Option<usize>,
    /// Keep at most this many strands, picked evenly through the file (`None`: all of them).
    pub max_strands: Option<usize>,
    /// Drop strands not longer than this (after scaling), counting them in
    /// [`HairModel::dropped_short`]: real files hold degenerate strands (AMD's Ratboy has strands
    /// of 10⁻⁵ units beside a median of 0.08) that the simulator would refuse. The default, 0,
    /// drops only strands of zero length.
    pub min_length: f32,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            scale: 1.0,
            up_axis: UpAxis::Y,
            nodes: None,
            max_strands: None,
            min_length: 0.0,
        }
    }
}

/// Strands read from a hair file: polylines, root first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HairModel {
    /// One polyline per kept strand, root (the vertex the simulator holds) first; ≥ 2 points each.
    pub strands: Vec<Vec<Vec3>>,
    /// Strands in the file.
    pub file_strands: usize,
    /// Strands dropped because they had fewer than two points or were not longer than
    /// [`ReadOptions::min_length`] (nothing to simulate).
    pub dropped_short: usize,
}

impl HairModel {
    /// Total number of points over the kept strands.
    #[must_use]
    pub fn points(&self) -> usize {
        self.strands.iter().map(Vec::len).sum()
    }

    /// The axis-aligned bounding box `(min, max)` of every point, or `None` with no strands.
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds_of(&self.strands)
    }
}

/// The axis-aligned bounding box of polylines, or `None` when there is no point.
#[must_use]
pub fn bounds_of<S: AsRef<[Vec3]>>(strands: &[S]) -> Option<(Vec3, Vec3)> {
    let mut points = strands.iter().flat_map(|s| s.as_ref().iter().copied());
    let first = points.next()?;
    Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
}

/// Why a hair file was refused. Offsets are in bytes from the start of the file.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HairFileError {
    /// The file is shorter than its fixed header.
    #[error("file too short for a {format} header: {len} bytes, need {need}")]
    ShortHeader {
        /// "HAIR" or "TressFX".
        format: &'static str,
        /// The file's length.
        len: usize,
        /// The header's length.
        need: usize,
    },
    /// The first four bytes are not `HAIR`.
    #[error("not a HAIR file: signature {0:?} at byte 0, expected \"HAIR\"")]
    BadSignature([u8; 4]),
    /// A TressFX version this reader does not know.
    #[error("unsupported TressFX version {0} at byte 0 (this reader takes 4.x)")]
    UnsupportedVersion(f32),
    /// A header field is out of range for reasons other than the file's size.
    #[error("header field `{field}` at byte {offset} is {value}: {why}")]
    BadField {
        /// The field's name as in the format's specification.
        field: &'static str,
        /// Where the field is.
        offset: usize,
        /// Its value.
        value: u64,
        /// What is wrong with it.
        why: &'static str,
    },
    /// An array the header announces runs past the end of the file (truncated or forged).
    #[error(
        "{array} array needs bytes {start}..{end} but the file has {len} bytes (truncated or forged header)"
    )]
    PastEnd {
        /// Which array.
        array: &'static str,
        /// Where it starts.
        start: u64,
        /// Where it would end (may exceed any real size for a forged header).
        end: u128,
        /// The file's length.
        len: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("strand {strand}, vertex {vertex}: non-finite coordinate at byte {offset}")]
    NonFinite {
        /// Strand index in the file.
        strand: usize,
        /// Vertex index within the strand.
        vertex: usize,
        /// Where the vertex starts.
        offset: usize,
    },
    /// An option is out of range.
    #[error("bad read option: {0}")]
    BadOption(&'static str),
    /// The file has no strand with at least two points.
    #[error("no strand with at least two points")]
    NoStrands,
    /// The file could not be read from disk.
    #[error("{path}: {message}")]
    Io {
        /// The path.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// A text file (OBJ, PLY, USDA) was refused by its reader.
    #[error("{path}: {message}")]
    Text {
        /// The path.
        path: String,
        /// The reader's message, with the line.
        message: String,
    },
    /// The path's extension names no format this module reads.
    #[error("{0}: unknown hair file extension (expected .hair, .tfx, .obj, .ply or .usda)")]
    UnknownExtension(String),
}

impl HairModel {
    /// Applies `options` (up axis, scale, strand picking, length filter, resampling) to
    /// polylines from elsewhere, e.g. the OBJ/PLY/USDA readers of [`crate::export`].
    ///
    /// # Errors
    /// Bad options, a non-finite coordinate (`offset` is then the vertex's index in the
    /// flattened point list), or no strand left.
    pub fn from_polylines<S: AsRef<[Vec3]>>(
        strands: &[S],
        options: &ReadOptions,
    ) -> Result<HairModel, HairFileError> {
        let mut first = 0;
        collect_strands(strands.len(), options, |strand| {
            let points = strands.get(strand).map_or(&[][..], AsRef::as_ref);
            let start = first;
            first += points.len();
            points
                .iter()
                .enumerate()
                .map(move |(k, p)| (start + k, p.to_array()))
        })
    }
}

/// Reads a hair file from disk, choosing the reader by extension: `.hair`, `.tfx`, or our own
/// text exports `.obj`, `.ply`, `.usda`.
///
/// # Errors
/// I/O errors, an unknown extension, or anything the readers refuse.
pub fn read_path(path: &Path, options: &ReadOptions) -> Result<HairModel, HairFileError> {
    let name = path.display().to_string();
    // An unknown extension is refused before the file is opened.
    reader_for(&name)?;
    let bytes = std::fs::read(path).map_err(|e| HairFileError::Io {
        path: name.clone(),
        message: e.to_string(),
    })?;
    read_bytes(&name, &bytes, options)
}

/// The hair-file formats, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FileFormat {
    Hair,
    Tfx,
    Obj,
    Ply,
    Usda,
}

/// Whether a file called `name` is a hair file this module reads, by its extension: `.hair`,
/// `.tfx`, or hairsim's own `.obj`, `.ply`, `.usda` exports.
#[must_use]
pub fn is_hair_file(name: &str) -> bool {
    reader_for(name).is_ok()
}

/// The format a file called `name` holds, by its extension.
fn reader_for(name: &str) -> Result<FileFormat, HairFileError> {
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("hair") => Ok(FileFormat::Hair),
        Some("tfx") => Ok(FileFormat::Tfx),
        Some("obj") => Ok(FileFormat::Obj),
        Some("ply") => Ok(FileFormat::Ply),
        Some("usda") => Ok(FileFormat::Usda),
        _ => Err(HairFileError::UnknownExtension(name.to_string())),
    }
}

/// Reads a hair file held in memory (a file dropped on the viewer's page), choosing the reader
/// by the extension of `name`, as [`read_path`] does.
///
/// # Errors
/// An unknown extension, a text format that is not UTF-8, or anything the readers refuse.
pub fn read_bytes(
    name: &str,
    bytes: &[u8],
    options: &ReadOptions,
) -> Result<HairModel, HairFileError> {
    type TextReader = fn(&str) -> Result<Vec<Vec<Vec3>>, crate::export::TextReadError>;
    let text_reader: TextReader = match reader_for(name)? {
        FileFormat::Hair => return read_hair(bytes, options),
        FileFormat::Tfx => return read_tfx(bytes, options),
        FileFormat::Obj => crate::export::read_obj,
        FileFormat::Ply => crate::export::read_ply,
        FileFormat::Usda => crate::export::read_usda,
    };
    let text = std::str::from_utf8(bytes).map_err(|e| HairFileError::Io {
        path: name.to_string(),
        message: format!("not UTF-8 text: {e}"),
    })?;
    let strands = text_reader(text).map_err(|e| HairFileError::Text {
        path: name.to_string(),
        message: e.to_string(),
    })?;
    HairModel::from_polylines(&strands, options)
}

/// Little-endian field access on a file already checked to be long enough.
pub(crate) fn u32_at(bytes: &[u8], offset: usize) -> Option<u32> {
    let b = bytes.get(offset..offset.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

pub(crate) fn f32_at(bytes: &[u8], offset: usize) -> Option<f32> {
    u32_at(bytes, offset).map(f32::from_bits)
}

/// Checks that `count` items of `item_bytes` each, starting at `start`, lie within the file.
/// Returns the end offset. Works in wide integers so a forged count cannot wrap.
pub(crate) fn check_array(
    array: &'static str,
    start: u64,
    count: u64,
    item_bytes: u64,
    len: usize,
) -> Result<u64, HairFileError> {
    let end = u128::from(start) + u128::from(count) * u128::from(item_bytes);
    if end > len as u128 {
        return Err(HairFileError::PastEnd {
            array,
            start,
            end,
            len,
        });
    }
    // Fits in u64 because it is at most the file's length.
    Ok(end as u64)
}

impl ReadOptions {
    pub(crate) fn validate(&self) -> Result<(), HairFileError> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(HairFileError::BadOption("scale must be finite and > 0"));
        }
        if matches!(self.nodes, Some(n) if n < 2) {
            return Err(HairFileError::BadOption("nodes must be at least 2"));
        }
        if !(self.min_length.is_finite() && self.min_length >= 0.0) {
            return Err(HairFileError::BadOption(
                "min_length must be finite and >= 0",
            ));
        }
        if self.max_strands == Some(0) {
            return Err(HairFileError::BadOption("max_strands must be at least 1"));
        }
        Ok(())
    }

    /// Which file strands to keep: all, or `max_strands` of them evenly spread.
    pub(crate) fn keeps(&self, strand: usize, file_strands: usize) -> bool {
        match self.max_strands {
            Some(k) if k < file_strands => {
                // Strand i is kept when it is the first at or after a multiple of file/k:
                // exactly k strands, evenly spread, decided without a list.
                // That is, i = ⌈m·n/k⌉ for some m: ⌊(i−1)k/n⌋ < ⌊ik/n⌋ (and i = 0 for m = 0).
                let (i, n, k) = (strand as u128, file_strands as u128, k as u128);
                i == 0 || (i * k) / n != ((i - 1) * k) / n
            }
            _ => true,
        }
    }
}

/// Builds the model from validated per-strand point ranges: `points(strand)` yields the file's
/// vertices of one strand, each with its byte offset. The caller has checked every range lies
/// within the file, so allocations here are bounded by the file's size (or by the resampling
/// count the caller chose).
pub(crate) fn collect_strands<I, F>(
    file_strands: usize,
    options: &ReadOptions,
    mut points: F,
) -> Result<HairModel, HairFileError>
where
    F: FnMut(usize) -> I,
    I: ExactSizeIterator<Item = (usize, [f32; 3])>,
{
    options.validate()?;
    let mut model = HairModel {
        strands: Vec::new(),
        file_strands,
        dropped_short: 0,
    };
    let mut polyline = Vec::new();
    for strand in 0..file_strands {
        // Called for every strand, in order, so readers can walk variable-length strands.
        let vertices = points(strand);
        if !options.keeps(strand, file_strands) {
            continue;
        }
        if vertices.len() < 2 {
            model.dropped_short += 1;
            continue;
        }
        polyline.clear();
        polyline.reserve(vertices.len());
        for (vertex, (offset, [x, y, z])) in vertices.enumerate() {
            // Checked after scaling too: a huge finite value times the scale can overflow.
            let p = options.up_axis.to_y_up(Vec3::new(x, y, z)) * options.scale;
            if !p.is_finite() {
                return Err(HairFileError::NonFinite {
                    strand,
                    vertex,
                    offset,
                });
            }
            polyline.push(p);
        }
        if polyline_length(&polyline) <= options.min_length {
            model.dropped_short += 1;
            continue;
        }
        let kept = match options.nodes {
            Some(n) => resample_polyline(&polyline, n),
            None => polyline.clone(),
        };
        model.strands.push(kept);
    }
    if model.strands.is_empty() {
        return Err(HairFileError::NoStrands);
    }
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{save, Format};

    #[test]
    fn read_path_reads_every_format_we_write() {
        let dir = std::env::temp_dir().join(format!("hairsim-read-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let strands: Vec<Vec<Vec3>> = (0..3)
            .map(|s| {
                (0..5)
                    .map(|i| Vec3::new(s as f32, 0.1 * i as f32, 0.0))
                    .collect()
            })
            .collect();
        // Z-up files come back rotated: (x, y, z) → (x, z, −y).
        let options = ReadOptions {
            up_axis: UpAxis::Z,
            ..ReadOptions::default()
        };
        for format in Format::ALL {
            let path = dir.join(format!("strands.{}", format.extension()));
            save(&path, &strands).unwrap();
            let model = read_path(&path, &options).unwrap();
            assert_eq!(model.strands.len(), 3, "{format:?}");
            assert_eq!(model.strands[1][4], Vec3::new(1.0, 0.0, -0.4), "{format:?}");
        }
        std::fs::write(dir.join("bad.obj"), "v 0 0 0\nl 1 5\n").unwrap();
        let e = read_path(&dir.join("bad.obj"), &options).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        assert!(matches!(
            read_path(&dir.join("x.abc"), &options),
            Err(HairFileError::UnknownExtension(_))
        ));
        assert!(matches!(
            read_path(&dir.join("missing.hair"), &options),
            Err(HairFileError::Io { .. })
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
