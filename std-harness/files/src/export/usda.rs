//! USD ASCII (`.usda`): one linear `BasisCurves` prim holding every strand.

use std::io::{BufWriter, Write};

use hairsim_core::Vec3;

use super::{check_strands, ExportError, Num, TextReadError};

/// Writes a `.usda` layer with a `BasisCurves` prim `/hair`: `type = "linear"`,
/// `curveVertexCounts`, `points` (root to tip, strand after strand) and a constant `widths`
/// of `width` (the strand diameter). The stage is Y-up in metres, as hairsim's world.
///
/// # Errors
/// I/O, a non-finite coordinate or width, or a strand with fewer than two points.
pub fn write_usda<W: Write, S: AsRef<[Vec3]>>(
    out: W,
    strands: &[S],
    width: f32,
) -> Result<(), ExportError> {
    check_strands(strands)?;
    if !(width.is_finite() && width >= 0.0) {
        return Err(ExportError::BadWidth(width));
    }
    let mut out = BufWriter::new(out);
    writeln!(out, "#usda 1.0")?;
    writeln!(out, "(")?;
    writeln!(out, "    defaultPrim = \"hair\"")?;
    writeln!(out, "    doc = \"hairsim strands\"")?;
    writeln!(out, "    metersPerUnit = 1")?;
    writeln!(out, "    upAxis = \"Y\"")?;
    writeln!(out, ")")?;
    writeln!(out)?;
    writeln!(out, "def BasisCurves \"hair\"")?;
    writeln!(out, "{{")?;
    writeln!(out, "    uniform token type = \"linear\"")?;
    writeln!(out, "    uniform token wrap = \"nonperiodic\"")?;
    // Bounds of the curves swept by their width, which USD asks of every boundable prim.
    if let Some((lo, hi)) = crate::hairfile::bounds_of(strands) {
        let (lo, hi) = (lo - Vec3::splat(0.5 * width), hi + Vec3::splat(0.5 * width));
        writeln!(
            out,
            "    float3[] extent = [({}, {}, {}), ({}, {}, {})]",
            Num(lo.x),
            Num(lo.y),
            Num(lo.z),
            Num(hi.x),
            Num(hi.y),
            Num(hi.z)
        )?;
    }
    write!(out, "    int[] curveVertexCounts = [")?;
    for (i, s) in strands.iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        write!(out, "{sep}{}", s.as_ref().len())?;
    }
    writeln!(out, "]")?;
    write!(out, "    point3f[] points = [")?;
    let mut first = true;
    for s in strands {
        for p in s.as_ref() {
            let sep = if first { "" } else { ", " };
            first = false;
            write!(out, "{sep}({}, {}, {})", Num(p.x), Num(p.y), Num(p.z))?;
        }
    }
    writeln!(out, "]")?;
    writeln!(out, "    float[] widths = [{}] (", Num(width))?;
    writeln!(out, "        interpolation = \"constant\"")?;
    writeln!(out, "    )")?;
    writeln!(out, "}}")?;
    out.flush()?;
    Ok(())
}

/// Reads the strands of a `.usda` holding one `BasisCurves` prim with `curveVertexCounts` and
/// `points` written inline (as [`write_usda`] does); other attributes are ignored.
///
/// # Errors
/// A missing attribute, a malformed number, counts that do not add up to the points, or a
/// non-finite coordinate.
pub fn read_usda(text: &str) -> Result<Vec<Vec<Vec3>>, TextReadError> {
    const F: &str = "USDA";
    let counts_text = array_after(text, "curveVertexCounts")?;
    let points_text = array_after(text, "points")?;
    let line_of = |s: &str| {
        text[..s.as_ptr() as usize - text.as_ptr() as usize]
            .lines()
            .count()
    };
    let mut counts = Vec::new();
    for token in counts_text
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
    {
        let n: usize = token.parse().map_err(|_| {
            TextReadError::new(F, line_of(counts_text), format!("bad count {token:?}"))
        })?;
        counts.push(n);
    }
    let mut points = Vec::new();
    let mut rest = points_text;
    while let Some(open) = rest.find('(') {
        let close = rest[open..]
            .find(')')
            .ok_or_else(|| TextReadError::new(F, line_of(rest), "unclosed point"))?;
        let tuple = &rest[open + 1..open + close];
        // The line number is counted only on error: counting it for every point would make
        // reading quadratic in the file's size.
        let point = parse_point(tuple).map_err(|mut e| {
            e.line = line_of(tuple);
            e
        })?;
        points.push(point);
        rest = &rest[open + close + 1..];
    }
    let total = counts.iter().try_fold(0usize, |a, &n| a.checked_add(n));
    if total != Some(points.len()) {
        return Err(TextReadError::new(
            F,
            line_of(counts_text),
            format!(
                "curveVertexCounts add up to {total:?}, but there are {} points",
                points.len()
            ),
        ));
    }
    let mut strands = Vec::with_capacity(counts.len());
    let mut at = 0;
    for n in counts {
        strands.push(points[at..at + n].to_vec());
        at += n;
    }
    Ok(strands)
}

/// `x, y, z` (line 0: the caller fills it in).
fn parse_point(tuple: &str) -> Result<Vec3, TextReadError> {
    let mut c = tuple.split(',').map(str::trim);
    let x = super::parse_coordinate("USDA", 0, c.next())?;
    let y = super::parse_coordinate("USDA", 0, c.next())?;
    let z = super::parse_coordinate("USDA", 0, c.next())?;
    if c.next().is_some() {
        return Err(TextReadError::new(
            "USDA",
            0,
            "point with more than 3 coordinates",
        ));
    }
    Ok(Vec3::new(x, y, z))
}

/// The text between the brackets of `name … = [ … ]`.
fn array_after<'a>(text: &'a str, name: &str) -> Result<&'a str, TextReadError> {
    let missing = || TextReadError::new("USDA", 0, format!("no `{name} = [...]` attribute"));
    let mut search = text;
    loop {
        let at = search.find(name).ok_or_else(missing)?;
        let after = search[at + name.len()..].trim_start();
        // The whole word, followed by `= [`.
        let word_start =
            at == 0 || !search[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_');
        if word_start {
            if let Some(value) = after.strip_prefix('=').map(str::trim_start) {
                if let Some(body) = value.strip_prefix('[') {
                    let end = body.find(']').ok_or_else(missing)?;
                    return Ok(&body[..end]);
                }
            }
        }
        search = &search[at + name.len()..];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::test_strands::{assert_same_bits, awkward};

    #[test]
    fn usda_round_trip_is_bit_exact() {
        let strands = awkward();
        let mut bytes = Vec::new();
        write_usda(&mut bytes, &strands, 8e-5).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        assert!(text.contains("int[] curveVertexCounts = [3, 2, 40]"));
        assert!(text.contains("uniform token type = \"linear\""));
        assert!(text.contains("float[] widths = [8e-5]"));
        assert!(text.contains("float3[] extent = [("));
        assert!(matches!(
            write_usda(Vec::new(), &strands, f32::NAN),
            Err(ExportError::BadWidth(_))
        ));
        assert_same_bits(&read_usda(&text).unwrap(), &strands);
    }

    #[test]
    fn usda_reader_refuses_mismatched_counts() {
        let text = "int[] curveVertexCounts = [2, 2]\npoint3f[] points = [(0, 0, 0), (1, 0, 0), (2, 0, 0)]\n";
        let e = read_usda(text).unwrap_err();
        assert!(e.message.contains("add up"), "{e}");
        assert!(read_usda("point3f[] points = [(0, 0, 0)]").is_err());
        let nan = "int[] curveVertexCounts = [2]\npoint3f[] points = [(0, 0, 0), (nan, 0, 0)]\n";
        assert_eq!(read_usda(nan).unwrap_err().line, 2);
    }
}
