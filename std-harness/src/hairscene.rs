//! The default scene around a hair file (`hairsim run head.hair`): the rod solver at 1 ms,
//! gravity, drag, bending, twist and inextensibility, the head still.

use std::path::Path;

use crate::run::HairFileOptions;
use crate::scene::{FileSpec, HairSpec, Scene, FORMAT};

/// The default scene for the hair file at `path`.
#[must_use]
pub fn scene_for_hair_file(path: &Path, options: &HairFileOptions) -> Scene {
    let name: String = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "hair".into())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .take(64)
        .collect();
    Scene {
        format: FORMAT,
        name: if name.is_empty() { "hair".into() } else { name },
        about: Some(format!("default scene around {}", path.display())),
        solver: "rod".into(),
        dt: 0.001,
        steps: Some(1000),
        duration: None,
        effects: ["gravity", "drag", "bending", "twist", "inextensibility"]
            .iter()
            .map(|e| (*e).to_string())
            .collect(),
        mode: None,
        gravity: None,
        drag: Some(2.0e-7),
        strands_per_block: None,
        material: None,
        rod: None,
        dftl: None,
        head: None,
        colliders: Vec::new(),
        hair: Some(HairSpec::File(FileSpec {
            path: path.display().to_string(),
            scale: options.scale,
            up: options.up.clone(),
        })),
        strands: Vec::new(),
        grabs: Vec::new(),
        wind: None,
        hair_hair: None,
        output: None,
    }
}
