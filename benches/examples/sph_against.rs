//! The SPH stage's physics against another version of it (`benches/sph_against.py` builds this
//! twice: with the checkout's stage and with an older one, and compares what they print).
//!
//! - `capture DIR`: runs each Table 1 scene with hair–hair at its own step on two threads and
//!   writes its state (every node's position and velocity, and the head's pose) after 0.5 s
//!   and after 1 s into `DIR`;
//! - `evaluate DIR OUT`: builds the stage anew on each captured state and writes each node's
//!   density and SPH acceleration, in strand order, into `OUT`, printing a line per state:
//!   the scene, the seconds and the node count;
//! - `volume`: runs Mannequin A for 1 s at its own step on two threads and prints the mean
//!   distance of its nodes from the head's centre, averaged over the steps.
//!
//! Files hold little-endian `f32`s.

use std::io::{Read, Write};
use std::path::Path;

use hairsim::sim::{scene_inputs, Sim};
use hairsim_benches::table1::{scene, Size, SIZES};
use hairsim_core::{DefaultMath, Pose, Quat, Strand, Vec3};

/// Seconds at which states are captured.
const CAPTURED: [f32; 2] = [0.5, 1.0];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize| args.get(k).map(String::as_str).unwrap_or_default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("a pool of two threads");
    pool.install(|| match arg(0) {
        "capture" => each_size(|size| capture_size(size, Path::new(arg(1)))),
        "evaluate" => {
            let mut out = std::fs::File::create(arg(2)).expect("the output file");
            each_size(|size| evaluate_size(size, Path::new(arg(1)), &mut out));
        }
        "volume" => println!("{:.6}", volume()),
        _ => {
            eprintln!("usage: sph_against capture DIR | evaluate DIR OUT | volume");
            std::process::exit(2);
        }
    });
}

/// Runs `f` for every Table 1 size with the strand length it needs.
fn each_size(mut f: impl FnMut(&Size) -> Result<(), String>) {
    for size in SIZES {
        if let Err(e) = f(size) {
            eprintln!("{}: {e}", size.name);
            std::process::exit(1);
        }
    }
}

fn capture_size(size: &Size, dir: &Path) -> Result<(), String> {
    match size.nodes {
        0..=16 => capture::<16>(size, dir),
        _ => capture::<32>(size, dir),
    }
}

fn evaluate_size(size: &Size, dir: &Path, out: &mut impl Write) -> Result<(), String> {
    match size.nodes {
        0..=16 => evaluate::<16>(size, dir, out),
        _ => evaluate::<32>(size, dir, out),
    }
}

fn state_file(dir: &Path, size: &Size, seconds: f32) -> std::path::PathBuf {
    dir.join(format!("{}-{seconds:.1}s.state", size.name))
}

fn capture<const N: usize>(size: &Size, dir: &Path) -> Result<(), String> {
    let prepared = scene(size, "dftl+shape+hair-hair", None);
    let mut sim = Sim::<N, DefaultMath>::new(&prepared, 2).map_err(|e| e.to_string())?;
    let dt = prepared.params.dt;
    let mut step = 0u64;
    for seconds in CAPTURED {
        let until = (seconds / dt).round() as u64;
        while step < until {
            sim.step(&scene_inputs::<DefaultMath>(&prepared, step));
            step += 1;
        }
        let head = sim.head;
        let pose = head
            .position
            .to_array()
            .into_iter()
            .chain(head.rotation.to_array());
        let nodes = sim.strands.iter().flat_map(|strand| {
            let n = strand.nodes();
            strand.state.position[..n]
                .iter()
                .chain(&strand.state.velocity[..n])
                .flat_map(|v| v.to_array())
        });
        let file: Vec<u8> = pose.chain(nodes).flat_map(f32::to_le_bytes).collect();
        std::fs::write(state_file(dir, size, seconds), file).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// The little-endian `f32`s of `path`.
fn floats(path: &Path) -> Result<Vec<f32>, String> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// Puts the captured state of `path` into `strands`; returns the head's pose.
fn restore<const N: usize>(strands: &mut [Strand<N>], path: &Path) -> Result<Pose, String> {
    let data = floats(path)?;
    let (pose, mut rest) = data.split_at(7);
    for strand in strands.iter_mut() {
        let n = strand.nodes();
        if rest.len() < 6 * n {
            return Err(format!("{}: too short", path.display()));
        }
        let (mine, after) = rest.split_at(6 * n);
        for (i, p) in mine[..3 * n].chunks_exact(3).enumerate() {
            strand.state.position[i] = Vec3::new(p[0], p[1], p[2]);
        }
        for (i, v) in mine[3 * n..].chunks_exact(3).enumerate() {
            strand.state.velocity[i] = Vec3::new(v[0], v[1], v[2]);
        }
        rest = after;
    }
    Ok(Pose {
        position: Vec3::new(pose[0], pose[1], pose[2]),
        rotation: Quat::from_xyzw(pose[3], pose[4], pose[5], pose[6]),
    })
}

fn evaluate<const N: usize>(size: &Size, dir: &Path, out: &mut impl Write) -> Result<(), String> {
    let prepared = scene(size, "dftl+shape+hair-hair", None);
    let mut sim = Sim::<N, DefaultMath>::new(&prepared, 2).map_err(|e| e.to_string())?;
    let params = *sim.sph.as_ref().ok_or("no hair-hair")?.params();
    for seconds in CAPTURED {
        let head = restore(&mut sim.strands, &state_file(dir, size, seconds))?;
        let mut sph = hairsim::sph::Sph::new(params, &sim.strands)?;
        let accelerations = sph
            .accelerations(&sim.strands, prepared.params.dt, head)
            .to_vec();
        let densities = sph.densities();
        let mut bytes = Vec::new();
        let mut p = 0;
        for (s, strand) in sim.strands.iter().enumerate() {
            for i in 0..strand.nodes() {
                let a = accelerations[s * N + i];
                for v in [densities[p], a.x, a.y, a.z] {
                    bytes.extend(v.to_le_bytes());
                }
                p += 1;
            }
        }
        out.write_all(&bytes).map_err(|e| e.to_string())?;
        // What was written, for the comparison to read it by.
        println!("{} {seconds:.1} {p}", size.name);
    }
    Ok(())
}

/// Mannequin A's mean distance of nodes from the head's centre (the head sphere's, at the
/// origin of the head's frame), m, averaged over 1 s of steps.
fn volume() -> f64 {
    let prepared = (hairsim::builtin::find("mannequin-a").unwrap().scene)()
        .prepare()
        .unwrap();
    let mut sim = Sim::<32, DefaultMath>::new(&prepared, 2).unwrap();
    let steps = (1.0 / prepared.params.dt).round() as u64;
    let mut total = 0.0f64;
    for k in 0..steps {
        sim.step(&scene_inputs::<DefaultMath>(&prepared, k));
        let centre = sim.head.position;
        let (mut sum, mut count) = (0.0f64, 0u64);
        for strand in &sim.strands {
            for &x in &strand.state.position[..strand.nodes()] {
                sum += f64::from((x - centre).length());
                count += 1;
            }
        }
        total += sum / count.max(1) as f64;
    }
    total / steps as f64
}
