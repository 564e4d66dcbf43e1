//! Cem Yuksel's binary HAIR format, written.

use std::io::{BufWriter, Write};

use hairsim_core::Vec3;

use super::{check_strands, ExportError};

/// Writes a HAIR file: a points array, and a segments array only when strands differ in length
/// (otherwise the header's default segment count says it, as in Yuksel's own models). `width`
/// goes in the default thickness. Readable back bit for bit with
/// [`read_hair`](crate::hairfile::read_hair) and default options.
///
/// # Errors
/// I/O, a non-finite coordinate, a strand with fewer than two or more than 65 536 points, or
/// more than `u32::MAX` strands or points.
pub fn write_hair<W: Write, S: AsRef<[Vec3]>>(
    out: W,
    strands: &[S],
    width: f32,
) -> Result<(), ExportError> {
    use crate::hairfile::yuksel_bits::{HAS_POINTS, HAS_SEGMENTS};
    check_strands(strands)?;
    if !(width.is_finite() && width >= 0.0) {
        return Err(ExportError::BadWidth(width));
    }
    let max = usize::from(u16::MAX) + 1;
    for (strand, s) in strands.iter().enumerate() {
        let points = s.as_ref().len();
        if points > max {
            return Err(ExportError::TooLong {
                strand,
                points,
                format: "HAIR",
                max,
            });
        }
    }
    let points: usize = strands.iter().map(|s| s.as_ref().len()).sum();
    let count =
        |what, n: usize| u32::try_from(n).map_err(|_| ExportError::TooMany { what, count: n });
    let strand_count = count("strands", strands.len())?;
    let point_count = count("points", points)?;
    let first = strands.first().map_or(2, |s| s.as_ref().len());
    let uniform = strands.iter().all(|s| s.as_ref().len() == first);
    let flags = if uniform {
        HAS_POINTS
    } else {
        HAS_POINTS | HAS_SEGMENTS
    };

    let mut out = BufWriter::new(out);
    let mut header = [0u8; 128];
    header[0..4].copy_from_slice(b"HAIR");
    header[4..8].copy_from_slice(&strand_count.to_le_bytes());
    header[8..12].copy_from_slice(&point_count.to_le_bytes());
    header[12..16].copy_from_slice(&flags.to_le_bytes());
    header[16..20].copy_from_slice(&((first - 1) as u32).to_le_bytes());
    header[20..24].copy_from_slice(&width.to_le_bytes());
    header[24..28].copy_from_slice(&0.0f32.to_le_bytes()); // opaque
    for (i, c) in [0.35f32, 0.22, 0.12].iter().enumerate() {
        header[28 + 4 * i..32 + 4 * i].copy_from_slice(&c.to_le_bytes());
    }
    let info = b"hairsim export: leader strands, Y up, metres";
    header[40..40 + info.len()].copy_from_slice(info);
    out.write_all(&header)?;
    if !uniform {
        for s in strands {
            // Checked above: 2 ..= 65 536 points, so 1 ..= 65 535 segments.
            out.write_all(&((s.as_ref().len() - 1) as u16).to_le_bytes())?;
        }
    }
    for s in strands {
        for p in s.as_ref() {
            for c in p.to_array() {
                out.write_all(&c.to_le_bytes())?;
            }
        }
    }
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::test_strands::{assert_same_bits, awkward, equal};
    use crate::hairfile::{read_hair, ReadOptions};

    #[test]
    fn hair_round_trip_is_bit_exact_with_and_without_segments_array() {
        for strands in [awkward(), equal()] {
            let mut bytes = Vec::new();
            write_hair(&mut bytes, &strands, 1e-4).unwrap();
            let points: usize = strands.iter().map(Vec::len).sum();
            let uniform = strands.iter().all(|s| s.len() == strands[0].len());
            let segments = if uniform { 0 } else { 2 * strands.len() };
            assert_eq!(bytes.len(), 128 + segments + 12 * points);
            let model = read_hair(&bytes, &ReadOptions::default()).unwrap();
            assert_same_bits(&model.strands, &strands);
            assert_eq!(model.file_strands, strands.len());
        }
    }

    #[test]
    fn hair_writer_refuses_strands_past_the_u16_limit() {
        let long = vec![vec![Vec3::ZERO; 65_537]];
        assert!(matches!(
            write_hair(Vec::new(), &long, 1e-4),
            Err(ExportError::TooLong { points: 65_537, .. })
        ));
        let line = |n: usize| {
            (0..n)
                .map(|i| Vec3::new(i as f32, 0.0, 0.0))
                .collect::<Vec<_>>()
        };
        let at_limit = vec![line(65_536), line(2)];
        let mut bytes = Vec::new();
        write_hair(&mut bytes, &at_limit, 1e-4).unwrap();
        let model = read_hair(&bytes, &ReadOptions::default()).unwrap();
        assert_eq!(model.strands[0].len(), 65_536);
    }
}
