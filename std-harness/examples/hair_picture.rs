//! Reads a `.hair` or `.tfx` file and draws it: `OUT_DIR/final.png`, `final.obj`, and a short
//! `run.gif` of the strands swaying (a rigid rotation about the roots' centre, no physics).
//!
//! ```text
//! cargo run -p hairsim --release --example hair_picture -- FILE OUT_DIR [--z-up] [--side] [--strands N]
//! ```

use std::path::PathBuf;
use std::time::Instant;

use hairsim::core::{Shape, Vec3};
use hairsim::export::{OutDir, OutOptions};
use hairsim::hairfile::{read_path, ReadOptions, UpAxis};
use hairsim::picture::View;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, out, flags @ ..] = args.as_slice() else {
        return Err("usage: hair_picture FILE OUT_DIR [--z-up] [--side] [--strands N]".into());
    };
    let mut options = ReadOptions::default();
    let mut view = View::Front;
    let mut flags = flags.iter();
    while let Some(flag) = flags.next() {
        match flag.as_str() {
            "--z-up" => options.up_axis = UpAxis::Z,
            "--side" => view = View::Side,
            "--strands" => options.max_strands = flags.next().map(|n| n.parse()).transpose()?,
            other => return Err(format!("unknown flag {other}").into()),
        }
    }
    let started = Instant::now();
    let model = read_path(&PathBuf::from(file), &options)?;
    let read = started.elapsed();
    let (lo, hi) = model.bounds().ok_or("no strands")?;
    println!(
        "{file}: {} of {} strands, {} points, bounds {lo} .. {hi}, read in {:.1} ms",
        model.strands.len(),
        model.file_strands,
        model.points(),
        read.as_secs_f64() * 1e3
    );
    // A stand-in head: a sphere under the roots' centre, a fifth of the model's height across.
    let roots: Vec<Vec3> = model.strands.iter().map(|s| s[0]).collect();
    let centre = roots.iter().copied().sum::<Vec3>() / roots.len() as f32;
    let radius = 0.2 * (hi - lo).max_element();
    let head = [Shape::Sphere {
        centre: centre - Vec3::Y * radius,
        radius,
    }];

    let mut dir = OutDir::create(
        out,
        OutOptions {
            view,
            ..OutOptions::default()
        },
    )?;
    let started = Instant::now();
    for k in 0..12u64 {
        let angle = 0.15 * (k as f32 * std::f32::consts::TAU / 12.0).sin();
        let (s, c) = angle.sin_cos();
        let swayed: Vec<Vec<Vec3>> = model
            .strands
            .iter()
            .map(|strand| {
                strand
                    .iter()
                    .map(|&p| {
                        let d = p - centre;
                        centre + Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z)
                    })
                    .collect()
            })
            .collect();
        dir.frame(k, &swayed, &head)?;
    }
    let gif = started.elapsed();
    let started = Instant::now();
    let written = dir.finish(&model.strands, &head)?;
    println!(
        "12 GIF frames in {:.0} ms; final.obj + final.png in {:.0} ms",
        gif.as_secs_f64() * 1e3,
        started.elapsed().as_secs_f64() * 1e3
    );
    for path in written {
        println!(
            "  {} ({} bytes)",
            path.display(),
            std::fs::metadata(&path)?.len()
        );
    }
    Ok(())
}
