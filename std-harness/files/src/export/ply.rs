//! Stanford PLY polylines, ASCII: a vertex element (x, y, z) and an edge element (vertex1,
//! vertex2) linking consecutive points of each strand.

use std::io::{BufWriter, Write};

use hairsim_core::Vec3;

use super::{check_strands, parse_coordinate, ExportError, Num, TextReadError};

/// Writes an ASCII PLY with every strand's points in order and an edge per segment.
///
/// # Errors
/// I/O, a non-finite coordinate, or a strand with fewer than two points.
pub fn write_ply<W: Write, S: AsRef<[Vec3]>>(out: W, strands: &[S]) -> Result<(), ExportError> {
    check_strands(strands)?;
    let mut out = BufWriter::new(out);
    let points: usize = strands.iter().map(|s| s.as_ref().len()).sum();
    let edges = points - strands.len();
    writeln!(out, "ply")?;
    writeln!(out, "format ascii 1.0")?;
    writeln!(
        out,
        "comment hairsim: {} strands, root to tip",
        strands.len()
    )?;
    writeln!(out, "element vertex {points}")?;
    for axis in ["x", "y", "z"] {
        writeln!(out, "property float {axis}")?;
    }
    writeln!(out, "element edge {edges}")?;
    writeln!(out, "property int vertex1")?;
    writeln!(out, "property int vertex2")?;
    writeln!(out, "end_header")?;
    for strand in strands {
        for p in strand.as_ref() {
            writeln!(out, "{} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
        }
    }
    let mut first = 0usize;
    for strand in strands {
        let n = strand.as_ref().len();
        for k in first..first + n - 1 {
            writeln!(out, "{k} {}", k + 1)?;
        }
        first += n;
    }
    out.flush()?;
    Ok(())
}

struct Element {
    name: String,
    count: usize,
    properties: Vec<String>,
}

/// Reads the polylines of an ASCII PLY with `vertex` (x, y, z among scalar properties) and
/// `edge` (vertex1, vertex2) elements: strands are the chains the edges form, each followed from
/// the vertex no edge enters. Vertices on no edge are ignored.
///
/// # Errors
/// A header other than ASCII 1.0 with scalar properties, a count that does not match the
/// body, a malformed number, an edge index out of range, or edges that do not form simple chains.
pub fn read_ply(text: &str) -> Result<Vec<Vec<Vec3>>, TextReadError> {
    const F: &str = "PLY";
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    match lines.next() {
        Some((_, l)) if l.trim() == "ply" => {}
        _ => return Err(TextReadError::new(F, 1, "missing \"ply\" magic")),
    }
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let (n, line) = lines
            .next()
            .ok_or_else(|| TextReadError::new(F, 0, "no end_header"))?;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["end_header"] => break,
            ["format", "ascii", "1.0"] | ["comment", ..] | ["obj_info", ..] | [] => {}
            ["format", ..] => return Err(TextReadError::new(F, n, "only ASCII 1.0 is read")),
            ["element", name, count] => elements.push(Element {
                name: (*name).to_string(),
                // Parsed, never preallocated: a forged count only fails the final check.
                count: count
                    .parse()
                    .map_err(|_| TextReadError::new(F, n, format!("bad count {count:?}")))?,
                properties: Vec::new(),
            }),
            ["property", "list", ..] => {
                return Err(TextReadError::new(F, n, "list properties are not read"))
            }
            ["property", _, name] => elements
                .last_mut()
                .ok_or_else(|| TextReadError::new(F, n, "property before any element"))?
                .properties
                .push((*name).to_string()),
            _ => {
                return Err(TextReadError::new(
                    F,
                    n,
                    format!("unknown header line {line:?}"),
                ))
            }
        }
    }
    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    for element in &elements {
        let column = |name: &str| element.properties.iter().position(|p| p == name);
        for _ in 0..element.count {
            let (n, line) = lines.next().ok_or_else(|| {
                TextReadError::new(F, 0, format!("body ends inside element {:?}", element.name))
            })?;
            let values: Vec<&str> = line.split_whitespace().collect();
            if values.len() != element.properties.len() {
                return Err(TextReadError::new(
                    F,
                    n,
                    format!(
                        "{} values for {} properties",
                        values.len(),
                        element.properties.len()
                    ),
                ));
            }
            let get = |name: &str| column(name).and_then(|c| values.get(c).copied());
            match element.name.as_str() {
                "vertex" => {
                    let x = parse_coordinate(F, n, get("x"))?;
                    let y = parse_coordinate(F, n, get("y"))?;
                    let z = parse_coordinate(F, n, get("z"))?;
                    vertices.push(Vec3::new(x, y, z));
                }
                "edge" => {
                    let index = |name: &str| -> Result<usize, TextReadError> {
                        let v = get(name).ok_or_else(|| {
                            TextReadError::new(F, n, format!("edge without {name}"))
                        })?;
                        v.parse()
                            .map_err(|_| TextReadError::new(F, n, format!("bad index {v:?}")))
                    };
                    edges.push((n, index("vertex1")?, index("vertex2")?));
                }
                _ => {}
            }
        }
    }
    chains(&vertices, &edges)
}

/// Follows edges `a → b` into polylines. Each vertex may have one edge out and one in.
fn chains(
    vertices: &[Vec3],
    edges: &[(usize, usize, usize)],
) -> Result<Vec<Vec<Vec3>>, TextReadError> {
    const F: &str = "PLY";
    let mut next = vec![None; vertices.len()];
    let mut entered = vec![false; vertices.len()];
    for &(line, a, b) in edges {
        if a >= vertices.len() || b >= vertices.len() || a == b {
            return Err(TextReadError::new(F, line, format!("bad edge {a} {b}")));
        }
        if next[a].is_some() || entered[b] {
            return Err(TextReadError::new(
                F,
                line,
                "edges branch: not a set of polylines",
            ));
        }
        next[a] = Some(b);
        entered[b] = true;
    }
    let mut strands = Vec::new();
    let mut walked = 0;
    for start in 0..vertices.len() {
        if entered[start] || next[start].is_none() {
            continue;
        }
        let mut strand = vec![vertices[start]];
        let mut at = start;
        while let Some(b) = next[at] {
            strand.push(vertices[b]);
            at = b;
        }
        walked += strand.len() - 1;
        strands.push(strand);
    }
    if walked != edges.len() {
        return Err(TextReadError::new(F, 0, "edges form a closed loop"));
    }
    Ok(strands)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::test_strands::{assert_same_bits, awkward};

    #[test]
    fn ply_round_trip_is_bit_exact() {
        let strands = awkward();
        let mut bytes = Vec::new();
        write_ply(&mut bytes, &strands).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        assert!(text.contains("element vertex 45\n"));
        assert!(text.contains("element edge 42\n"));
        assert_same_bits(&read_ply(&text).unwrap(), &strands);
    }

    #[test]
    fn ply_reader_refuses_forged_counts_branches_and_loops() {
        let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n";
        let body = "0 0 0\n1 0 0\n2 0 0\n";
        assert_eq!(
            read_ply(&format!("{header}{body}0 1\n1 2\n"))
                .unwrap()
                .len(),
            1
        );
        assert!(
            read_ply(&format!("{header}{body}0 1\n0 2\n")).is_err(),
            "branch"
        );
        assert!(
            read_ply(&format!("{header}{body}0 1\n1 0\n")).is_err(),
            "loop"
        );
        assert!(
            read_ply(&format!("{header}{body}0 1\n1 9\n")).is_err(),
            "index"
        );
        assert!(
            read_ply(&format!("{header}{body}0 1\n")).is_err(),
            "truncated"
        );
        let forged = header.replace("vertex 3", "vertex 18446744073709551615");
        assert!(read_ply(&format!("{forged}{body}0 1\n1 2\n")).is_err());
        assert!(read_ply("ply\nformat binary_little_endian 1.0\nend_header\n").is_err());
    }
}
