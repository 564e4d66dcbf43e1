//! Sánchez-Banderas 2015 Table 1's scenes as the benches and studies build them: Mannequin A
//! and B (the built-in scenes), and scalps with the strand and vertex counts of Horse Louis,
//! Bunny and Hectroll, each with the effects of a Table 1 column.

use hairsim::scene::{HairSpec, Prepared, Scene};

/// A Table 1 size: name, strands, nodes per strand (vertices = strands × nodes; the paper's
/// count in the comment where it is not a multiple).
pub struct Size {
    /// The name a bench's filter picks it by.
    pub name: &'static str,
    /// Strands (the scalp's leaders).
    pub strands: u32,
    /// Nodes a strand.
    pub nodes: u32,
}

pub const SIZES: &[Size] = &[
    // 349,232 in the paper: 23.3 a strand.
    Size {
        name: "mannequin-a",
        strands: 15_000,
        nodes: 23,
    },
    Size {
        name: "mannequin-b",
        strands: 500,
        nodes: 16,
    },
    // 32,041 in the paper: 9.5 a strand.
    Size {
        name: "horse-louis",
        strands: 3_358,
        nodes: 10,
    },
    Size {
        name: "bunny",
        strands: 2_902,
        nodes: 12,
    },
    // 5,710 in the paper: 11.5 a strand.
    Size {
        name: "hectroll",
        strands: 496,
        nodes: 12,
    },
];

/// Table 1's columns.
pub const COLUMNS: &[&str] = &["dftl", "dftl+shape", "dftl+shape+hair-hair"];

/// The mannequin scene (DFTL + shape + hair–hair) with `size`'s strands and nodes, the effects
/// of `column`, at a step of `dt` (the scene's own when `None`).
pub fn scene(size: &Size, column: &str, dt: Option<f32>) -> Prepared {
    let mut scene: Scene = (hairsim::builtin::find("mannequin-a").unwrap().scene)();
    if let Some(dt) = dt {
        scene.dt = dt;
    }
    if let Some(HairSpec::Scalp(scalp)) = &mut scene.hair {
        scalp.leaders = size.strands;
        scalp.nodes = size.nodes;
    }
    match column {
        "dftl" => scene.effects.retain(|e| e != "shape" && e != "hair-hair"),
        "dftl+shape" => scene.effects.retain(|e| e != "hair-hair"),
        _ => {}
    }
    scene.prepare().unwrap()
}
