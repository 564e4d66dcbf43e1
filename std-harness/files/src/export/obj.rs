//! Wavefront OBJ polylines.

use std::io::{BufWriter, Write};

use hairsim_core::Vec3;

use super::{check_strands, parse_coordinate, ExportError, Num, TextReadError};

/// Writes `v` lines strand by strand, root to tip, then one `l` line per strand.
///
/// # Errors
/// I/O, a non-finite coordinate, or a strand with fewer than two points.
pub fn write_obj<W: Write, S: AsRef<[Vec3]>>(out: W, strands: &[S]) -> Result<(), ExportError> {
    check_strands(strands)?;
    let mut out = BufWriter::new(out);
    let points: usize = strands.iter().map(|s| s.as_ref().len()).sum();
    writeln!(
        out,
        "# hairsim: {} strands, {points} points, root to tip",
        strands.len()
    )?;
    writeln!(out, "o hair")?;
    for strand in strands {
        for p in strand.as_ref() {
            writeln!(out, "v {} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        }
    }
    let mut next = 1usize; // OBJ indices are 1-based
    for strand in strands {
        write!(out, "l")?;
        for _ in strand.as_ref() {
            write!(out, " {next}")?;
            next += 1;
        }
        writeln!(out)?;
    }
    out.flush()?;
    Ok(())
}

/// Reads the polylines of an OBJ file: every `l` line is a strand, in the order of its indices.
/// Accepts negative (relative) indices and `v/vt` forms; ignores every other statement.
///
/// # Errors
/// A malformed `v` or `l` line, an index out of range, or a non-finite coordinate.
pub fn read_obj(text: &str) -> Result<Vec<Vec<Vec3>>, TextReadError> {
    const F: &str = "OBJ";
    let mut vertices = Vec::new();
    let mut strands = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let x = parse_coordinate(F, line_no, tokens.next())?;
                let y = parse_coordinate(F, line_no, tokens.next())?;
                let z = parse_coordinate(F, line_no, tokens.next())?;
                vertices.push(Vec3::new(x, y, z));
            }
            Some("l") => {
                let mut strand = Vec::new();
                for token in tokens {
                    let index = token.split('/').next().unwrap_or(token);
                    let index: i64 = index.parse().map_err(|_| {
                        TextReadError::new(F, line_no, format!("bad index {token:?}"))
                    })?;
                    let resolved = match index {
                        i if i > 0 => usize::try_from(i - 1).ok(),
                        i if i < 0 => usize::try_from(i.unsigned_abs())
                            .ok()
                            .and_then(|back| vertices.len().checked_sub(back)),
                        _ => None,
                    };
                    let p = resolved.and_then(|k| vertices.get(k)).ok_or_else(|| {
                        TextReadError::new(
                            F,
                            line_no,
                            format!(
                                "index {index} out of range ({} vertices so far)",
                                vertices.len()
                            ),
                        )
                    })?;
                    strand.push(*p);
                }
                strands.push(strand);
            }
            _ => {}
        }
    }
    Ok(strands)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::test_strands::{assert_same_bits, awkward};

    #[test]
    fn obj_round_trip_is_bit_exact() {
        let strands = awkward();
        let mut bytes = Vec::new();
        write_obj(&mut bytes, &strands).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        assert_same_bits(&read_obj(&text).unwrap(), &strands);
        // The layout the design asks for: v lines first, then one l line per strand.
        let l_lines: Vec<&str> = text.lines().filter(|l| l.starts_with("l ")).collect();
        assert_eq!(l_lines.len(), 3);
        assert_eq!(l_lines[0], "l 1 2 3");
        assert_eq!(l_lines[1], "l 4 5");
    }

    #[test]
    fn obj_reader_takes_relative_indices_and_refuses_bad_ones() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nl -3 -2/7 -1\n";
        let s = read_obj(text).unwrap();
        assert_eq!(s, vec![vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)]]);
        let e = read_obj("v 0 0 0\nl 1 2\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(read_obj("v 0 nan 0\n")
            .unwrap_err()
            .message
            .contains("non-finite"));
        assert!(read_obj("l 0\n").is_err());
        assert!(read_obj("v 1 2\n").is_err());
    }

    #[test]
    fn writers_refuse_nan_and_single_points() {
        let nan = vec![vec![Vec3::ZERO, Vec3::new(0.0, f32::NAN, 0.0)]];
        assert!(matches!(
            write_obj(Vec::new(), &nan),
            Err(ExportError::NonFinite {
                strand: 0,
                vertex: 1
            })
        ));
        let short = vec![vec![Vec3::ZERO, Vec3::X], vec![Vec3::ZERO]];
        assert!(matches!(
            write_obj(Vec::new(), &short),
            Err(ExportError::TooShort {
                strand: 1,
                points: 1
            })
        ));
    }
}
