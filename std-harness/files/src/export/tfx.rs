//! AMD TressFX 4.x `.tfx`, written.

use std::io::{BufWriter, Write};

use hairsim_core::Vec3;

use super::{check_strands, ExportError};

/// Writes a TressFX 4.0 file: the 160-byte header then `float4` positions. Nodes 0 and 1 get
/// `w = 0` (pinned, as hairsim holds them), the rest `w = 1`. Every strand must have the same
/// number of points (resample with [`resample_polyline`](crate::hairfile::resample_polyline)).
///
/// # Errors
/// I/O, a non-finite coordinate, fewer than two points, unequal strand lengths, or counts past
/// `u32`.
pub fn write_tfx<W: Write, S: AsRef<[Vec3]>>(out: W, strands: &[S]) -> Result<(), ExportError> {
    check_strands(strands)?;
    let first = strands.first().map_or(2, |s| s.as_ref().len());
    if let Some((strand, s)) = strands
        .iter()
        .enumerate()
        .find(|(_, s)| s.as_ref().len() != first)
    {
        return Err(ExportError::UnequalStrands {
            strand,
            points: s.as_ref().len(),
            first,
        });
    }
    let count =
        |what, n: usize| u32::try_from(n).map_err(|_| ExportError::TooMany { what, count: n });
    let strand_count = count("strands", strands.len())?;
    let vertices = count("vertices per strand", first)?;
    // The position array must end within u32 offsets' reach for readers that use 32-bit sizes.
    count("bytes", 160 + 16 * first * strands.len())?;

    let mut out = BufWriter::new(out);
    let mut header = [0u8; 160];
    header[0..4].copy_from_slice(&4.0f32.to_le_bytes());
    header[4..8].copy_from_slice(&strand_count.to_le_bytes());
    header[8..12].copy_from_slice(&vertices.to_le_bytes());
    header[12..16].copy_from_slice(&160u32.to_le_bytes());
    out.write_all(&header)?;
    for s in strands {
        for (i, p) in s.as_ref().iter().enumerate() {
            let inverse_mass = if i < 2 { 0.0f32 } else { 1.0 };
            for c in [p.x, p.y, p.z, inverse_mass] {
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
    use crate::hairfile::{read_tfx, ReadOptions};

    #[test]
    fn tfx_round_trip_is_bit_exact() {
        let strands = equal();
        let mut bytes = Vec::new();
        write_tfx(&mut bytes, &strands).unwrap();
        assert_eq!(bytes.len(), 160 + 16 * 5 * 8);
        let model = read_tfx(&bytes, &ReadOptions::default()).unwrap();
        assert_same_bits(&model.strands, &strands);
    }

    #[test]
    fn tfx_writer_refuses_unequal_strands() {
        assert!(matches!(
            write_tfx(Vec::new(), &awkward()),
            Err(ExportError::UnequalStrands { strand: 1, .. })
        ));
    }
}
