//! Cem Yuksel's HAIR format (<http://www.cemyuksel.com/research/hairmodels>).
//!
//! A 128-byte little-endian header — `"HAIR"`, strand count, point count, a bit field saying
//! which arrays follow, the default segment count (used when there is no segments array),
//! default thickness, transparency and colour, and 88 bytes of text — then, in this order and
//! each present only when its bit is set: segments (`u16` per strand: points − 1), points
//! (3 × `f32` per point, root to tip, strand after strand), thickness (`f32` per point),
//! transparency (`f32` per point), colours (3 × `f32` per point).

use super::{check_array, collect_strands, f32_at, u32_at, HairFileError, HairModel, ReadOptions};

/// Length of the fixed header.
pub const HAIR_HEADER_BYTES: usize = 128;

/// Bit of the header's array field: a segments array follows.
pub const HAS_SEGMENTS: u32 = 1 << 0;
/// Bit: a points array follows.
pub const HAS_POINTS: u32 = 1 << 1;
/// Bit: a thickness array follows.
pub const HAS_THICKNESS: u32 = 1 << 2;
/// Bit: a transparency array follows.
pub const HAS_TRANSPARENCY: u32 = 1 << 3;
/// Bit: a colour array follows.
pub const HAS_COLOURS: u32 = 1 << 4;

const STRANDS_AT: usize = 4;
const POINTS_AT: usize = 8;
const FLAGS_AT: usize = 12;
const DEFAULT_SEGMENTS_AT: usize = 16;

/// Reads a HAIR file held in memory.
///
/// # Errors
/// A short or foreign header, a count that disagrees with another or with the file's size,
/// an array past the end of the file, a non-finite coordinate (naming strand, vertex and byte
/// offset), bad options, or no strand with two points.
pub fn read_hair(bytes: &[u8], options: &ReadOptions) -> Result<HairModel, HairFileError> {
    options.validate()?;
    let len = bytes.len();
    let header = bytes
        .get(..HAIR_HEADER_BYTES)
        .ok_or(HairFileError::ShortHeader {
            format: "HAIR",
            len,
            need: HAIR_HEADER_BYTES,
        })?;
    let signature = [header[0], header[1], header[2], header[3]];
    if &signature != b"HAIR" {
        return Err(HairFileError::BadSignature(signature));
    }
    let field = |at| u32_at(header, at).unwrap_or(0);
    let strands = u64::from(field(STRANDS_AT));
    let points = u64::from(field(POINTS_AT));
    let flags = field(FLAGS_AT);
    let default_segments = u64::from(field(DEFAULT_SEGMENTS_AT));
    if flags & HAS_POINTS == 0 {
        return Err(HairFileError::BadField {
            field: "arrays",
            offset: FLAGS_AT,
            value: u64::from(flags),
            why: "no points array: nothing to read",
        });
    }

    // Lay every announced array out against the file's length before reading any of it.
    let mut end = HAIR_HEADER_BYTES as u64;
    let segments_at = end;
    if flags & HAS_SEGMENTS != 0 {
        end = check_array("segments", end, strands, 2, len)?;
    }
    let points_at = end;
    end = check_array("points", end, points, 12, len)?;
    for (bit, name, item) in [
        (HAS_THICKNESS, "thickness", 4),
        (HAS_TRANSPARENCY, "transparency", 4),
        (HAS_COLOURS, "colours", 12),
    ] {
        if flags & bit != 0 {
            end = check_array(name, end, points, item, len)?;
        }
    }

    // The strands' point counts must add up to the header's point count.
    let segment_count = |strand: u64| -> u64 {
        if flags & HAS_SEGMENTS == 0 {
            return default_segments;
        }
        let at = segments_at + 2 * strand;
        bytes
            .get(at as usize..at as usize + 2)
            .map_or(0, |b| u64::from(u16::from_le_bytes([b[0], b[1]])))
    };
    let total: u128 = if flags & HAS_SEGMENTS == 0 {
        u128::from(strands) * (u128::from(default_segments) + 1)
    } else {
        // Bounded: the segments array fits in the file, so `strands` ≤ len / 2.
        (0..strands).map(|s| u128::from(segment_count(s) + 1)).sum()
    };
    if total != u128::from(points) {
        return Err(HairFileError::BadField {
            field: "point count",
            offset: POINTS_AT,
            value: points,
            why: if flags & HAS_SEGMENTS == 0 {
                "differs from strands × (default segments + 1)"
            } else {
                "differs from the sum of the segments array + 1 per strand"
            },
        });
    }

    // From here every strand's points lie inside the checked points array.
    // Checked above: every index and offset below is at most the file's length, so fits usize.
    let points_at = points_at as usize;
    let mut next_point = 0usize;
    collect_strands(strands as usize, options, |strand| {
        let count = segment_count(strand as u64) as usize + 1;
        let first = next_point;
        next_point += count;
        (first..first + count).map(move |k| {
            let at = points_at + 12 * k;
            let coordinate = |i: usize| f32_at(bytes, at + 4 * i).unwrap_or(f32::NAN);
            (at, [coordinate(0), coordinate(1), coordinate(2)])
        })
    })
}
