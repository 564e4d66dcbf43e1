//! Fuzz seeds: small valid files made by our own writers (never the sample files).

use std::path::Path;

use hairsim_core::Vec3;

use super::{write_hair, write_obj, write_ply, write_tfx, write_usda, ExportError};

/// Small valid files, `(file name, bytes)`, from our own writers: HAIR with and without a
/// segments array, TressFX, OBJ, PLY and USDA. The fuzz targets of `read_hair` and `read_tfx`
/// start from these.
///
/// # Errors
/// Only if a writer fails, which would be a bug.
pub fn fuzz_seeds() -> Result<Vec<(String, Vec<u8>)>, ExportError> {
    let wavy = |s: usize, n: usize| -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = i as f32 / (n - 1) as f32;
                Vec3::new(
                    0.01 * s as f32 + 0.005 * (6.0 * t).sin(),
                    -0.1 * t,
                    0.002 * s as f32,
                )
            })
            .collect()
    };
    let equal: Vec<Vec<Vec3>> = (0..3).map(|s| wavy(s, 4)).collect();
    let unequal: Vec<Vec<Vec3>> = vec![wavy(0, 2), wavy(1, 5), wavy(2, 3)];
    let mut seeds = Vec::new();
    let mut add = |name: &str, write: &dyn Fn(&mut Vec<u8>) -> Result<(), ExportError>| {
        let mut bytes = Vec::new();
        write(&mut bytes).map(|()| seeds.push((name.to_string(), bytes)))
    };
    add("uniform.hair", &|b| write_hair(b, &equal, 1e-4))?;
    add("segments.hair", &|b| write_hair(b, &unequal, 1e-4))?;
    add("guides.tfx", &|b| write_tfx(b, &equal))?;
    add("strands.obj", &|b| write_obj(b, &unequal))?;
    add("strands.ply", &|b| write_ply(b, &unequal))?;
    add("strands.usda", &|b| write_usda(b, &unequal, 1e-4))?;
    Ok(seeds)
}

/// Writes [`fuzz_seeds`] into `dir` (created if needed), one file each.
///
/// # Errors
/// I/O.
pub fn write_fuzz_seeds(dir: &Path) -> Result<(), ExportError> {
    std::fs::create_dir_all(dir)?;
    for (name, bytes) in fuzz_seeds()? {
        std::fs::write(dir.join(name), bytes)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::{read_obj, read_ply, read_usda};
    use crate::hairfile::{read_hair, read_tfx, ReadOptions};

    #[test]
    fn every_seed_reads_back() {
        let o = ReadOptions::default();
        for (name, bytes) in fuzz_seeds().unwrap() {
            let strands = match name.rsplit('.').next().unwrap() {
                "hair" => read_hair(&bytes, &o).unwrap().strands,
                "tfx" => read_tfx(&bytes, &o).unwrap().strands,
                "obj" => read_obj(std::str::from_utf8(&bytes).unwrap()).unwrap(),
                "ply" => read_ply(std::str::from_utf8(&bytes).unwrap()).unwrap(),
                "usda" => read_usda(std::str::from_utf8(&bytes).unwrap()).unwrap(),
                other => panic!("unexpected seed kind {other}"),
            };
            assert_eq!(strands.len(), 3, "{name}");
            assert!(
                bytes.len() < 2048,
                "{name} is {} bytes: seeds stay small",
                bytes.len()
            );
        }
    }
}
