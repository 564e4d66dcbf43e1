//! Running one configuration of a study and measuring it against the reference.

use std::time::Instant;

use anyhow::{anyhow, Result};
use hairsim_core::math::FastMath;
use hairsim_core::{Libm, Math, Vec3};

use super::{arc_lengths, point_at, Backend, Config, Row};
use crate::groom::{self, Groom};
use crate::run::capacity_for;
use crate::scene::Prepared;
use crate::sim::{scene_inputs, Sim};

/// Times at which the energy is sampled: this many, evenly over the run (the last at its end).
pub const ENERGY_SAMPLES: usize = 10;

/// What one run leaves behind.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// Final node positions, per strand.
    pub positions: Vec<Vec<Vec3>>,
    /// Rest arc length of each node from the root, per strand, m.
    pub rest_arc: Vec<Vec<f64>>,
    /// Mechanical energy (kinetic plus gravitational, every node) at the sample times, J.
    pub energy: Vec<f64>,
    /// `Σ m |g| L` over strands, J: the scale of energy errors.
    pub energy_scale: f64,
    /// Largest relative stretch of a segment over the run.
    pub max_stretch: f64,
    /// Median step time, µs.
    pub us_per_step: f64,
    /// Steps taken.
    pub steps: u64,
    /// Strands rolled back.
    pub rolled_back: u64,
    /// Whether the state stayed finite.
    pub finite: bool,
    /// The groom at the end against the rest groom ([`crate::groom`]).
    pub groom: Groom,
}

/// Runs `prepared` for `duration` simulated seconds on one thread with `backend`, timing
/// every step.
///
/// Every configuration runs at the harness's largest capacity, [`MAX_NODES`](super::MAX_NODES)
/// nodes, whatever its strands: the rows' costs then compare like with like (the capacity
/// changes no bit of a run, but it changes the cost: a strand of 16 nodes takes a few per cent
/// more instructions at capacity 32 than at 16), and each backend compiles the simulation once.
pub fn simulate(prepared: &Prepared, backend: Backend, duration: f64) -> Result<Trace> {
    // The error for a strand longer than any capacity of this build.
    capacity_for(prepared.max_nodes())?;
    const N: usize = super::MAX_NODES;
    match backend {
        Backend::Libm => simulate_n::<N, Libm>(prepared, duration),
        Backend::FastMath => simulate_n::<N, FastMath>(prepared, duration),
    }
}

fn simulate_n<const N: usize, M: Math>(prepared: &Prepared, duration: f64) -> Result<Trace> {
    let mut sim = Sim::<N, M>::new(prepared, 1).map_err(|e| anyhow!("{e}"))?;
    let dt = f64::from(prepared.params.dt);
    let steps = ((duration / dt).round() as u64).max(1);
    let gravity = sim.params.gravity;
    let energy_at: Vec<u64> = (1..=ENERGY_SAMPLES as u64)
        .map(|i| (steps * i / ENERGY_SAMPLES as u64).max(1))
        .collect();
    let mut energy = Vec::with_capacity(ENERGY_SAMPLES);
    let mut times = Vec::with_capacity(steps as usize);
    let mut max_stretch = 0.0f64;
    let mut rolled_back = 0u64;
    for k in 0..steps {
        let inputs = scene_inputs::<M>(prepared, k);
        let start = Instant::now();
        let report = sim.step(&inputs);
        times.push(start.elapsed().as_secs_f64());
        max_stretch = max_stretch.max(f64::from(report.max_stretch));
        rolled_back += u64::from(report.rolled_back);
        if energy_at.contains(&(k + 1)) {
            energy.push(mechanical_energy(&sim.strands, gravity));
        }
    }
    let rest_arc = sim
        .strands
        .iter()
        .map(|s| arc_lengths(&s.rest.position[..s.nodes()]))
        .collect();
    let g = f64::from(gravity.length());
    let energy_scale = sim
        .strands
        .iter()
        .map(|s| {
            let n = s.nodes();
            let mass: f64 = s.rest.mass[..n].iter().map(|&m| f64::from(m)).sum();
            let length: f64 = s.rest.segment_length[..n - 1]
                .iter()
                .map(|&l| f64::from(l))
                .sum();
            mass * g * length
        })
        .sum::<f64>();
    Ok(Trace {
        positions: sim.strands.iter().map(|s| s.positions().to_vec()).collect(),
        rest_arc,
        energy,
        energy_scale,
        max_stretch,
        us_per_step: crate::run::median_ms(&mut times) * 1e3,
        steps,
        rolled_back,
        finite: sim.is_finite(),
        groom: groom::measure(&sim.strands),
    })
}

/// Kinetic plus gravitational potential energy of every node, J.
fn mechanical_energy<const N: usize>(strands: &[hairsim_core::Strand<N>], gravity: Vec3) -> f64 {
    strands
        .iter()
        .map(|s| {
            (0..s.nodes())
                .map(|i| {
                    let m = f64::from(s.rest.mass[i]);
                    let v = s.state.velocity[i];
                    0.5 * m * f64::from(v.dot(v)) - m * f64::from(gravity.dot(s.state.position[i]))
                })
                .sum::<f64>()
        })
        .sum()
}

/// RMS distance between `trace` and `reference` at the reference's nodes, m: each reference
/// node is compared with the point of the same strand at the same fraction of its rest length
/// (the same node when both have the same nodes).
#[must_use]
pub fn rms_distance(trace: &Trace, reference: &Trace) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for (s, ref_points) in reference.positions.iter().enumerate() {
        let (Some(points), Some(arc), Some(ref_arc)) = (
            trace.positions.get(s),
            trace.rest_arc.get(s),
            reference.rest_arc.get(s),
        ) else {
            return f64::INFINITY;
        };
        let length = arc.last().copied().unwrap_or(0.0);
        let ref_length = ref_arc
            .last()
            .copied()
            .unwrap_or(0.0)
            .max(f64::MIN_POSITIVE);
        for (p, a) in ref_points.iter().zip(ref_arc) {
            let q = point_at(points, arc, a / ref_length * length);
            sum += f64::from(p.distance_squared(q));
            count += 1;
        }
    }
    (sum / count.max(1) as f64).sqrt()
}

/// The row of `config` from its run `trace` against `reference`.
#[must_use]
pub fn compare(config: Config, trace: &Trace, reference: &Trace) -> Row {
    let scale = reference.energy_scale.max(f64::MIN_POSITIVE);
    let energy_error = trace
        .energy
        .iter()
        .zip(&reference.energy)
        .map(|(e, r)| (e - r).abs() / scale)
        .fold(0.0, f64::max);
    let rms = rms_distance(trace, reference);
    let finite = trace.finite && rms.is_finite();
    Row {
        config,
        us_per_step: trace.us_per_step,
        us_per_ms: trace.us_per_step * 1e-3 / f64::from(config.dt),
        rms_distance: if finite { rms } else { f64::INFINITY },
        max_stretch: trace.max_stretch,
        energy_error,
        rolled_back: trace.rolled_back,
        groom: trace.groom,
        finite,
        stable: finite && trace.rolled_back == 0 && trace.max_stretch <= super::STABLE_STRETCH,
        pareto: false,
    }
}
