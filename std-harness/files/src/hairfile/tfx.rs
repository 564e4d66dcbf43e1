//! AMD TressFX 4.x `.tfx` files.
//!
//! A 160-byte little-endian header — version (`f32`), strand count, vertices per strand (the
//! same for every strand), then byte offsets from the start of the file of the vertex positions
//! (`float4` per vertex: x, y, z and w = inverse mass, strand after strand, root first), strand
//! UVs (`float2` per strand), vertex UVs (`float2` per vertex), strand thickness (`f32` per
//! strand) and vertex colours (`float4` per vertex), an offset of 0 meaning "absent" — and 32
//! reserved words. The `w = 0` pinning marks are ignored: exporters pin one or two root
//! vertices, while hairsim always holds nodes 0 and 1.

use super::{check_array, collect_strands, f32_at, u32_at, HairFileError, HairModel, ReadOptions};

/// Length of the fixed header.
pub const TFX_HEADER_BYTES: usize = 160;

const STRANDS_AT: usize = 4;
const VERTICES_AT: usize = 8;
const POSITIONS_AT: usize = 12;

/// Reads a TressFX 4.x file held in memory.
///
/// # Errors
/// A short header, another version, fewer than two vertices per strand, an offset inside the
/// header, an array past the end of the file, a non-finite coordinate (naming strand, vertex and
/// byte offset), bad options, or no strand.
pub fn read_tfx(bytes: &[u8], options: &ReadOptions) -> Result<HairModel, HairFileError> {
    options.validate()?;
    let len = bytes.len();
    let header = bytes
        .get(..TFX_HEADER_BYTES)
        .ok_or(HairFileError::ShortHeader {
            format: "TressFX",
            len,
            need: TFX_HEADER_BYTES,
        })?;
    let field = |at| u32_at(header, at).unwrap_or(0);
    let version = f32_at(header, 0).unwrap_or(f32::NAN);
    if !(4.0..5.0).contains(&version) {
        return Err(HairFileError::UnsupportedVersion(version));
    }
    let strands = u64::from(field(STRANDS_AT));
    let vertices = u64::from(field(VERTICES_AT));
    if vertices < 2 {
        // Also what bounds the strand count by the file's size below.
        return Err(HairFileError::BadField {
            field: "numVerticesPerStrand",
            offset: VERTICES_AT,
            value: vertices,
            why: "a strand needs at least 2 vertices",
        });
    }
    let positions_at = u64::from(field(POSITIONS_AT));
    if positions_at < TFX_HEADER_BYTES as u64 {
        return Err(HairFileError::BadField {
            field: "offsetVertexPosition",
            offset: POSITIONS_AT,
            value: positions_at,
            why: "points inside the header",
        });
    }
    let total = u64::from(field(STRANDS_AT)) * vertices;
    check_array("vertex position", positions_at, total, 16, len)?;
    // Arrays we do not read must still lie inside the file, or it is truncated or forged.
    for (at, name, count, item) in [
        (16, "strand UV", strands, 8),
        (20, "vertex UV", total, 8),
        (24, "strand thickness", strands, 4),
        (28, "vertex colour", total, 16),
    ] {
        let start = u64::from(field(at));
        if start != 0 {
            check_array(name, start, count, item, len)?;
        }
    }

    // Checked above: every index and offset below is at most the file's length, so fits usize.
    let (vertices, positions_at) = (vertices as usize, positions_at as usize);
    collect_strands(strands as usize, options, |strand| {
        let first = strand * vertices;
        (first..first + vertices).map(move |k| {
            let at = positions_at + 16 * k;
            let coordinate = |i: usize| f32_at(bytes, at + 4 * i).unwrap_or(f32::NAN);
            (at, [coordinate(0), coordinate(1), coordinate(2)])
        })
    })
}
