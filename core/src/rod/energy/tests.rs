//! Finite-difference tests of the rod energies, in `f64` ([`F64`]): forces against the energy
//! they claim to derive from, on random bent, stretched and twisted strands around straight,
//! wavy and helical rest shapes, with the root clamped and with an interior clamp.
//!
//! The reference energies are built from the frames alone, independently of the gradient
//! code: the root frame moves by time-parallel transport, a clamped segment's material vector
//! likewise (docs/architecture.md), free angles are either held (hair-optimised twist:
//! `F = −∂E/∂x` at fixed `θ`) or re-minimised by Newton (`F = −dE/dx`).

use super::*;
use crate::frames::transport_in_time;
use crate::precision::F64;
use crate::rod::twist::{
    newton_twist, twist_newton_system, ClampedFrames, NewtonSettings, NewtonSystem,
};
use glam::DVec3;

pub(crate) const NODES: usize = 12;
type Rest = RodRest<NODES, f64>;
type Frames = RodFrames<F64, NODES>;

/// xorshift64*: reproducible random numbers in `[-1, 1]`.
pub(crate) struct Rng(pub u64);

impl Rng {
    pub(crate) fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        bits as f64 / (1u64 << 52) as f64 - 1.0
    }
    fn vector(&mut self) -> DVec3 {
        DVec3::new(self.next(), self.next(), self.next())
    }
}

/// Rest shapes with unit-ish segments: straight, a planar wave, a helix.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Shape {
    Straight,
    Wavy,
    Helix,
}

pub(crate) fn rest_points(shape: Shape) -> [DVec3; NODES] {
    core::array::from_fn(|i| {
        let s = i as f64;
        match shape {
            Shape::Straight => DVec3::new(0.0, -s, 0.0),
            Shape::Wavy => DVec3::new(0.35 * (1.1 * s).sin(), -s, 0.0),
            Shape::Helix => DVec3::new(0.8 * (0.9 * s).cos(), -0.5 * s, 0.8 * (0.9 * s).sin()),
        }
    })
}

fn rest(points: &[DVec3; NODES], mu: f64) -> Rest {
    Rest::compute::<F64>(points, 1.0, mu, 0.7, 1.0)
}

fn frames(x: &[DVec3; NODES], u0: DVec3, rest: &Rest) -> Frames {
    Frames::compute(x, u0, &rest.rest_length)
}

fn root_tangent(x: &[DVec3; NODES]) -> DVec3 {
    (x[1] - x[0]).normalize()
}

/// A configuration: positions, angles, root Bishop vector.
#[derive(Clone, Copy)]
struct Config {
    x: [DVec3; NODES],
    theta: [f64; NODES],
    u0: DVec3,
}

fn rest_config(points: &[DVec3; NODES], rest: &Rest) -> Config {
    Config {
        x: *points,
        theta: rest.rest_theta,
        u0: crate::frames::perpendicular_unit_by_reciprocal::<F64>(root_tangent(points)),
    }
}

/// Rest shape moved by up to `amplitude` per coordinate, angles by up to 1 rad.
fn random_config(points: &[DVec3; NODES], rest: &Rest, rng: &mut Rng, amplitude: f64) -> Config {
    let base = rest_config(points, rest);
    let mut c = base;
    for x in c.x.iter_mut() {
        *x += rng.vector() * amplitude;
    }
    for t in c.theta.iter_mut() {
        *t += rng.next();
    }
    c.u0 = transport_in_time::<F64>(root_tangent(&base.x), root_tangent(&c.x), base.u0);
    c
}

/// The energy at positions `x` reached from `base`: root frame and clamped material frames
/// moved by time-parallel transport, free angles held or re-minimised by Newton.
fn energy_at(
    x: &[DVec3; NODES],
    base: &Config,
    rest: &Rest,
    clamped: &ClampedSegments,
    minimise: bool,
) -> f64 {
    let u0 = transport_in_time::<F64>(root_tangent(&base.x), root_tangent(x), base.u0);
    let saved = ClampedFrames::save(&frames(&base.x, base.u0, rest), &base.theta, clamped);
    let f = frames(x, u0, rest);
    let mut theta = base.theta;
    saved.transport(&f, clamped, &mut theta);
    if minimise {
        newton_twist(
            &f,
            rest,
            clamped,
            ElasticTerms::ALL,
            NewtonSettings {
                iterations: 60,
                tolerance: 1e-14,
                fixed_cost: false,
            },
            &mut theta,
        );
    }
    elastic_energy(&f, &theta, rest, ElasticTerms::ALL)
}

/// `max_i |F_i + ∇_i E| / max_i |∇_i E|` with `∇E` by central differences.
fn force_error(base: &Config, rest: &Rest, clamped: &ClampedSegments, minimise: bool) -> f64 {
    let f = frames(&base.x, base.u0, rest);
    let mut forces = [DVec3::ZERO; NODES];
    elastic_forces(
        &f,
        &base.theta,
        rest,
        clamped,
        ElasticTerms::ALL,
        &mut forces,
    );
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for i in 0..NODES {
        let mut gradient = DVec3::ZERO;
        for axis in 0..3 {
            let mut plus = base.x;
            let mut minus = base.x;
            plus[i][axis] += h;
            minus[i][axis] -= h;
            gradient[axis] = (energy_at(&plus, base, rest, clamped, minimise)
                - energy_at(&minus, base, rest, clamped, minimise))
                / (2.0 * h);
        }
        worst = worst.max((forces[i] + gradient).length());
        scale = scale.max(gradient.length());
    }
    assert!(
        scale > 1e-3,
        "a test configuration without forces proves nothing"
    );
    worst / scale
}

const SHAPES: [Shape; 3] = [Shape::Straight, Shape::Wavy, Shape::Helix];

fn clamped_sets() -> [ClampedSegments; 2] {
    let mut interior = ClampedSegments::ROOT_ONLY;
    assert!(interior.insert(6));
    [ClampedSegments::ROOT_ONLY, interior]
}

#[test]
fn forces_are_minus_the_partial_gradient_at_fixed_theta() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut worst: f64 = 0.0;
    for shape in SHAPES {
        for mu in [1.0, 2.5] {
            let points = rest_points(shape);
            let rest = rest(&points, mu);
            for clamped in clamped_sets() {
                for _ in 0..3 {
                    let c = random_config(&points, &rest, &mut rng, 0.25);
                    let e = force_error(&c, &rest, &clamped, false);
                    assert!(
                        e < 1e-7,
                        "{shape:?} µ = {mu} {clamped:?}: relative error {e:e}"
                    );
                    worst = worst.max(e);
                }
            }
        }
    }
    std::println!("fixed θ: worst relative force error {worst:.2e}");
}

#[test]
fn forces_are_minus_the_total_gradient_with_the_newton_twist() {
    let mut rng = Rng(0x0ddb_a11c_afe5_eed5);
    let mut worst: f64 = 0.0;
    for shape in SHAPES {
        for mu in [1.0, 2.5] {
            let points = rest_points(shape);
            let rest = rest(&points, mu);
            for clamped in clamped_sets() {
                for _ in 0..2 {
                    let mut c = random_config(&points, &rest, &mut rng, 0.25);
                    let f = frames(&c.x, c.u0, &rest);
                    let outcome = newton_twist(
                        &f,
                        &rest,
                        &clamped,
                        ElasticTerms::ALL,
                        NewtonSettings {
                            iterations: 60,
                            tolerance: 1e-14,
                            fixed_cost: false,
                        },
                        &mut c.theta,
                    );
                    assert!(outcome.converged, "{outcome:?}");
                    let e = force_error(&c, &rest, &clamped, true);
                    assert!(
                        e < 1e-7,
                        "{shape:?} µ = {mu} {clamped:?}: relative error {e:e}"
                    );
                    worst = worst.max(e);
                }
            }
        }
    }
    std::println!("Newton twist: worst relative force error {worst:.2e}");
}

#[test]
fn twist_derivative_and_newton_hessian_match_finite_differences() {
    let mut rng = Rng(0x5eed_0000_0000_0001);
    for shape in SHAPES {
        let points = rest_points(shape);
        let rest = rest(&points, 1.8);
        for clamped in clamped_sets() {
            let c = random_config(&points, &rest, &mut rng, 0.2);
            let f = frames(&c.x, c.u0, &rest);
            let energy = |theta: &[f64; NODES]| elastic_energy(&f, theta, &rest, ElasticTerms::ALL);
            let system = |theta: &[f64; NODES]| {
                let mut system = NewtonSystem::<f64, NODES>::default();
                let t = &theta[..NODES - 1];
                twist_newton_system(&f, &rest, &clamped, ElasticTerms::ALL, t, &mut system);
                (system.gradient, system.full, system.coupling)
            };
            let h = 1e-6;
            let (g, full, coupling) = system(&c.theta);
            for j in 0..NODES - 1 {
                let mut plus = c.theta;
                let mut minus = c.theta;
                plus[j] += h;
                minus[j] -= h;
                let fd = (energy(&plus) - energy(&minus)) / (2.0 * h);
                let exact = twist_derivative(&f, &c.theta, &rest, ElasticTerms::ALL, j);
                assert!(
                    (fd - exact).abs() < 1e-7 * (1.0 + fd.abs()),
                    "j = {j}: {fd} vs {exact}"
                );
                if clamped.contains(j) {
                    assert_eq!(g[j], 0.0);
                    continue;
                }
                assert!((g[j] - exact).abs() < 1e-12 * (1.0 + exact.abs()));
                // Hessian column j by differences of the gradient.
                let (gp, _, _) = system(&plus);
                let (gm, _, _) = system(&minus);
                let column = |r: usize| (gp[r] - gm[r]) / (2.0 * h);
                assert!(
                    (column(j) - full[j]).abs() < 1e-6 * (1.0 + full[j].abs()),
                    "H_jj"
                );
                if j + 1 < NODES - 1 && !clamped.contains(j + 1) {
                    assert!((column(j + 1) - coupling[j + 1]).abs() < 1e-6, "H_j,j+1");
                }
            }
        }
    }
}

#[test]
fn curvature_binormal_gradient_matches_finite_differences_with_stretch() {
    // The holonomy form is exact for stretched segments: a 30 % stretch still passes.
    let mut rng = Rng(42);
    let points = rest_points(Shape::Helix);
    let rest = rest(&points, 1.0);
    let mut c = random_config(&points, &rest, &mut rng, 0.05);
    for (i, x) in c.x.iter_mut().enumerate() {
        *x *= 1.0 + 0.03 * i as f64;
    }
    c.u0 = transport_in_time::<F64>(root_tangent(&points), root_tangent(&c.x), c.u0);
    let e = force_error(&c, &rest, &ClampedSegments::ROOT_ONLY, false);
    std::println!("stretched helix: relative force error {e:.2e}");
    assert!(e < 1e-6, "{e:e}");
}

#[test]
fn rest_shapes_have_no_energy_and_no_force_under_both_twists() {
    for shape in SHAPES {
        for mu in [1.0, 3.0] {
            let points = rest_points(shape);
            let rest = rest(&points, mu);
            let c = rest_config(&points, &rest);
            let f = frames(&c.x, c.u0, &rest);
            assert!(elastic_energy(&f, &c.theta, &rest, ElasticTerms::ALL).abs() < 1e-24);
            let mut forces = [DVec3::ZERO; NODES];
            let clamped = ClampedSegments::ROOT_ONLY;
            elastic_forces(
                &f,
                &c.theta,
                &rest,
                &clamped,
                ElasticTerms::ALL,
                &mut forces,
            );
            assert!(forces.iter().all(|v| v.length() < 1e-12), "{shape:?}");
            let mut theta = c.theta;
            crate::rod::twist::hair_optimised_twist(
                &f,
                &rest,
                &clamped,
                ElasticTerms::ALL,
                &mut theta[..NODES - 1],
            );
            for (a, b) in theta.iter().zip(&c.theta) {
                assert!((a - b).abs() < 1e-12, "{shape:?}: {a} vs {b}");
            }
            let mut theta = c.theta;
            newton_twist(
                &f,
                &rest,
                &clamped,
                ElasticTerms::ALL,
                NewtonSettings {
                    iterations: 10,
                    tolerance: 1e-12,
                    fixed_cost: false,
                },
                &mut theta,
            );
            for (a, b) in theta.iter().zip(&c.theta) {
                assert!((a - b).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn frames_recomputed_in_place_equal_fresh_ones() {
    // The rod step reuses one frames buffer per step (`RodFrames::recompute`): every entry
    // must be what a fresh `compute` gives, whatever the buffer held before.
    let mut rng = Rng(0x5eed_f4a3);
    for shape in [Shape::Straight, Shape::Wavy, Shape::Helix] {
        let points = rest_points(shape);
        let rest = rest(&points, 1.0);
        let mut buffer = Frames::empty();
        for _ in 0..4 {
            let c = random_config(&points, &rest, &mut rng, 0.3);
            buffer.recompute(&c.x, c.u0, &rest.rest_length);
            let fresh = frames(&c.x, c.u0, &rest);
            assert_eq!(
                std::format!("{buffer:?}"),
                std::format!("{fresh:?}"),
                "{shape:?}"
            );
        }
    }
}
