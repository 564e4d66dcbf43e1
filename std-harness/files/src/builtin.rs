//! The built-in scenes `hairsim scenes` lists. Each is a [`Scene`] value — the same structure
//! a scene file loads into — so built-ins, files and recordings share one code path.
//!
//! The papers' scenarios: Kmoch 2009 Table 1 (`stand-1` … `stand-3`, `head-1` … `head-3`;
//! strand counts there include the followers) and Sánchez-Banderas 2015 Table 1
//! (`mannequin-a`: 15,000 strands, ~349,000 vertices; `mannequin-b`: 500 strands, 8,000
//! vertices; both with DFTL + shape + hair–hair, the table's third column).

use hairsim_core::scenes::{firmware, firmware_dftl, haptic_dftl};
use hairsim_core::{DefaultMath, Math, Params, Shake, World};

use crate::scene::generate::{self, Style};
use crate::scene::{
    ColliderSpec, GrabSpec, HairSpec, HeadSpec, KeyframesSpec, MotionSpec, PathKey, ScalpSpec,
    Scene, ShakeSpec, StandSpec, StrandSpec, StyleSpec, FORMAT,
};

/// A built-in scene.
#[derive(Clone, Copy, Debug)]
pub struct Builtin {
    /// Name, as typed on the command line.
    pub name: &'static str,
    /// One line for `hairsim scenes`.
    pub about: &'static str,
    /// The scene.
    pub scene: fn() -> Scene,
}

/// The scene `hairsim run` runs when none is named.
pub const DEFAULT_SCENE: &str = "firmware";

/// Every built-in scene.
pub const BUILTINS: &[Builtin] = &[
    Builtin {
        name: "firmware",
        about: "the firmware example's scene: 4 rod strands of 12-15 nodes on a 5 cm head shaking at 10 rad/s, one tip grabbed on a circle, every rod stage on, 1000 steps at 1 ms (same hash as under QEMU)",
        scene: firmware_scene,
    },
    Builtin {
        name: "firmware-dftl",
        about: "the firmware example's DFTL scene: 8 wavy strands with shape and gusty wind on a 5 cm head shaking at 10 rad/s above a floor, 1000 steps at 1 ms (same hash as under QEMU)",
        scene: firmware_dftl_scene,
    },
    Builtin {
        name: "haptic-dftl",
        about: "a device holds a DFTL strand's tip through a coupling (50 N/m) on a 1 cm circle: 8 wavy strands x 16 nodes with shape, head shaking at 10 rad/s, 1000 steps at 1 ms (same hash as under QEMU)",
        scene: haptic_dftl_scene,
    },
    Builtin {
        name: "stand-1",
        about: "Kmoch 2009 Stand #1: 3 long wisps (leaders of 30 nodes, 30 cm) on a stand, 69 followers, falling from horizontal",
        scene: || stand("stand-1", 3, 30, 0.30, 23, 0.05),
    },
    Builtin {
        name: "stand-2",
        about: "Kmoch 2009 Stand #2: 3 short wisps (leaders of 5 nodes, 5 cm) on a stand, 69 followers",
        scene: || stand("stand-2", 3, 5, 0.05, 23, 0.05),
    },
    Builtin {
        name: "stand-3",
        about: "Kmoch 2009 Stand #3: 18 short wisps (leaders of 5 nodes, 5 cm) on a stand, 432 followers",
        scene: || stand("stand-3", 18, 5, 0.05, 24, 0.02),
    },
    Builtin {
        name: "head-1",
        about: "Kmoch 2009 Head #1: 50 straight leaders x 30 nodes, 5,000 followers, on a head shaking at 10 rad/s",
        scene: || head("head-1", 50, 5000, false),
    },
    Builtin {
        name: "head-2",
        about: "Kmoch 2009 Head #2: 25 straight leaders x 30 nodes, 2,475 followers, on a head shaking at 10 rad/s",
        scene: || head("head-2", 25, 2475, false),
    },
    Builtin {
        name: "head-3",
        about: "Kmoch 2009 Head #3: 25 wavy leaders x 30 nodes, 2,475 followers, on a head shaking at 10 rad/s",
        scene: || head("head-3", 25, 2475, true),
    },
    Builtin {
        name: "mannequin-a",
        about: "Sanchez-Banderas 2015 Mannequin A: 15,000 DFTL strands x 23 nodes (345,000 vertices; the paper's 349,232) with shape preservation and hair-hair (SPH) on a turning mannequin",
        scene: || mannequin("mannequin-a", 15_000, 23),
    },
    Builtin {
        name: "mannequin-b",
        about: "Sanchez-Banderas 2015 Mannequin B: 500 DFTL strands x 16 nodes (8,000 vertices) with shape preservation and hair-hair (SPH) on a turning mannequin",
        scene: || mannequin("mannequin-b", 500, 16),
    },
    Builtin {
        name: "haptic",
        about: "a grab drags the tip region of a 30-node wisp sideways and back; the grab force is reported (--json: grab_forces)",
        scene: haptic,
    },
];

/// The built-in scene called `name`.
#[must_use]
pub fn find(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

fn base(name: &str, about: &str, solver: &str, dt: f32, steps: u64, effects: &[&str]) -> Scene {
    Scene {
        format: FORMAT,
        name: name.into(),
        about: Some(about.into()),
        solver: solver.into(),
        dt,
        steps: Some(steps),
        duration: None,
        effects: effects.iter().map(|e| (*e).to_string()).collect(),
        mode: None,
        gravity: None,
        drag: None,
        strands_per_block: None,
        material: None,
        rod: None,
        dftl: None,
        head: None,
        colliders: Vec::new(),
        hair: None,
        strands: Vec::new(),
        grabs: Vec::new(),
        wind: None,
        hair_hair: None,
        output: None,
    }
}

fn about(name: &str) -> &'static str {
    find(name).map_or("", |b| b.about)
}

const ROD_EFFECTS: &[&str] = &["gravity", "drag", "bending", "twist", "inextensibility"];

/// The head shaking at 10 rad/s of Kmoch 2009's Head scenes (`Shake::TEN_RAD_PER_S`).
fn ten_rad_per_s() -> HeadSpec {
    let s = Shake::TEN_RAD_PER_S;
    HeadSpec {
        motion: Some(MotionSpec::Shake(ShakeSpec {
            axis: s.axis.to_array(),
            centre: None,
            amplitude: s.amplitude,
            frequency: Some(s.frequency),
            peak_speed: None,
        })),
    }
}

fn sphere(centre: [f32; 3], radius: f32) -> ColliderSpec {
    ColliderSpec {
        shape: "sphere".into(),
        attached: Some(true),
        centre: Some(centre),
        radius: Some(radius),
        a: None,
        b: None,
        point: None,
        normal: None,
    }
}

fn capsule(a: [f32; 3], b: [f32; 3], radius: f32) -> ColliderSpec {
    ColliderSpec {
        shape: "capsule".into(),
        attached: Some(true),
        centre: None,
        radius: Some(radius),
        a: Some(a),
        b: Some(b),
        point: None,
        normal: None,
    }
}

/// The firmware's scene, taken from `hairsim_core::scenes::firmware` itself (its strands,
/// parameters and collider), so that its hash stays the firmware's.
#[must_use]
pub fn firmware_scene() -> Scene {
    let mut world: Box<World<{ firmware::STRANDS }, { firmware::NODES }, DefaultMath>> =
        Box::default();
    // The firmware scene is fixed and valid; a failure here would leave the world empty and the
    // scene would be refused by its check ("no strands"), never run half-built.
    let _ = firmware::build(&mut world);
    let mut scene = from_world("firmware", &world, u64::from(firmware::STEPS));
    scene.grabs = world.grabs().iter().map(circling).collect();
    scene
}

/// A firmware scene's grab as a scene's: `firmware::grab_target` and
/// `haptic_dftl::grab_target` go round a 1 cm circle at 2 Hz in the x–z plane from the grab's
/// first target (the target before step k is the circle at t = (k + 1) dt, as here).
fn circling(grab: &hairsim_core::Grab) -> GrabSpec {
    GrabSpec {
        strand: grab.strand,
        node: grab.node,
        force_limit: grab.force_limit,
        coupling: grab.coupling.map(|c| crate::scene::CouplingSpec {
            stiffness: c.stiffness,
            damping: c.damping,
        }),
        path: None,
        circle: Some(crate::scene::CircleSpec {
            start: grab.target.to_array(),
            radius: 0.01,
            frequency: 2.0,
            u: None,
            v: None,
        }),
        release: None,
    }
}

/// The haptic DFTL scene, from `hairsim_core::scenes::haptic_dftl`.
#[must_use]
pub fn haptic_dftl_scene() -> Scene {
    let mut world: Box<World<{ haptic_dftl::STRANDS }, { haptic_dftl::NODES }, DefaultMath>> =
        Box::default();
    let _ = haptic_dftl::build(&mut world);
    let mut scene = from_world("haptic-dftl", &world, u64::from(haptic_dftl::STEPS));
    scene.grabs = world.grabs().iter().map(circling).collect();
    scene
}

/// The firmware's DFTL scene, from `hairsim_core::scenes::firmware_dftl`.
#[must_use]
pub fn firmware_dftl_scene() -> Scene {
    let mut world: Box<World<{ firmware_dftl::STRANDS }, { firmware_dftl::NODES }, DefaultMath>> =
        Box::default();
    let _ = firmware_dftl::build(&mut world);
    from_world("firmware-dftl", &world, u64::from(firmware_dftl::STEPS))
}

/// A scene that builds exactly the strands, colliders and parameters of a core `World` (the
/// firmware's scenes), with the head shaking at 10 rad/s as their `input` functions do.
fn from_world<const S: usize, const N: usize, M: Math>(
    name: &str,
    world: &World<S, N, M>,
    steps: u64,
) -> Scene {
    let params: &Params = world.params();
    let mut scene = base(
        name,
        about(name),
        params.solver.name(),
        params.dt,
        steps,
        &[],
    );
    scene.effects = params
        .effects
        .iter()
        .map(|e| e.name().to_string())
        .collect();
    scene.mode = Some(params.mode.name().into());
    scene.gravity = Some(params.gravity.to_array());
    scene.drag = Some(params.drag);
    scene.head = Some(ten_rad_per_s());
    // With either solver: DFTL's held strands take the rod's projection, with its caps.
    let r = params.rod;
    scene.rod = Some(crate::scene::RodSpec {
        twist: Some(r.twist.name().into()),
        projection_iterations: Some(u32::from(r.projection_iterations)),
        projection_tolerance: Some(r.projection_tolerance),
        newton_iterations: Some(u32::from(r.newton_iterations)),
        newton_tolerance: Some(r.newton_tolerance),
    });
    if params.solver == hairsim_core::Solver::Dftl {
        let d = params.dftl;
        scene.dftl = Some(crate::scene::DftlSpec {
            damping: Some(d.damping),
            global_shape: Some(d.global_shape),
            local_shape: Some(d.local_shape),
            reference_dt: Some(d.reference_dt),
            global_shape_fade: Some(d.global_shape_fade),
            local_shape_fade: Some(d.local_shape_fade),
        });
    }
    if params.effects.contains(hairsim_core::Effect::Wind) {
        let w = params.wind;
        scene.wind = Some(crate::scene::WindSpec {
            direction: w.direction.to_array(),
            strength: w.strength,
            gust: Some(w.gust),
            gust_frequency: Some(w.gust_frequency),
            seed: Some(w.seed),
        });
    }
    scene.colliders = world
        .colliders()
        .iter()
        .map(|c| match c.shape {
            hairsim_core::Shape::Sphere { centre, radius } => ColliderSpec {
                attached: Some(c.attached_to_head),
                ..sphere(centre.to_array(), radius)
            },
            hairsim_core::Shape::Capsule { a, b, radius } => ColliderSpec {
                attached: Some(c.attached_to_head),
                ..capsule(a.to_array(), b.to_array(), radius)
            },
            hairsim_core::Shape::Plane { point, normal } => ColliderSpec {
                shape: "plane".into(),
                attached: Some(c.attached_to_head),
                centre: None,
                radius: None,
                a: None,
                b: None,
                point: Some(point.to_array()),
                normal: Some(normal.to_array()),
            },
        })
        .collect();
    scene.strands = world
        .strands()
        .iter()
        .map(|s| StrandSpec {
            points: Some(
                s.rest.position[..s.nodes()]
                    .iter()
                    .map(|p| p.to_array())
                    .collect(),
            ),
            ..StrandSpec::default()
        })
        .collect();
    scene
}

fn stand(name: &str, wisps: u32, nodes: u32, length: f32, followers: u32, spacing: f32) -> Scene {
    let mut scene = base(name, about(name), "rod", 0.001, 2000, ROD_EFFECTS);
    scene.drag = Some(2.0e-7);
    scene.hair = Some(HairSpec::Stand(StandSpec {
        wisps,
        nodes,
        length,
        spacing: Some(spacing),
        origin: None,
        direction: None,
        followers: Some(followers),
        style: None,
    }));
    scene
}

fn head(name: &str, leaders: u32, followers: u32, wavy: bool) -> Scene {
    let mut effects = ROD_EFFECTS.to_vec();
    effects.push("collisions");
    // Wavy strands on the shaking head diverged at 1 ms with the state-dependent substep
    // count (stretch 1e7 after ~300 steps) and ran at 0.5 ms; with the fixed count they hold
    // at 1 ms (2000 steps, both twists: finite, no rollback, stretch ≤ 1e-5).
    let (dt, steps) = (0.001, 2000);
    let mut scene = base(name, about(name), "rod", dt, steps, &effects);
    scene.drag = Some(2.0e-7);
    scene.head = Some(ten_rad_per_s());
    scene.colliders = vec![sphere([0.0, 0.0, 0.0], 0.1)];
    scene.hair = Some(HairSpec::Scalp(ScalpSpec {
        leaders,
        nodes: 30,
        length: 0.3,
        centre: None,
        radius: Some(0.1),
        cap_angle: Some(1.2),
        followers: Some(followers),
        style: wavy.then(|| StyleSpec {
            shape: Some("wavy".into()),
            amplitude: Some(0.01),
            period: Some(0.1),
            radius: None,
        }),
    }));
    scene
}

/// The paper's mannequin at two levels of detail (Table 1: Mannequin A and B): the same head,
/// body and 25 cm of hair, `leaders` strands of `nodes` nodes, with DFTL, shape preservation and
/// hair–hair interaction (the table's third column), at the paper's Δt of 1/60 s.
fn mannequin(name: &str, leaders: u32, nodes: u32) -> Scene {
    let effects = [
        "gravity",
        "drag",
        "inextensibility",
        "collisions",
        "shape",
        "hair-hair",
    ];
    let mut scene = base(name, about(name), "dftl", 1.0 / 60.0, 600, &effects);
    scene.drag = Some(2.0e-7);
    // The paper's shape fractions at the paper's step (Sánchez-Banderas 2015 Sec. 5): this
    // scene runs at 60 Hz, where they hold as given.
    scene.dftl = Some(crate::scene::DftlSpec {
        global_shape: Some(0.1),
        local_shape: Some(0.3),
        reference_dt: Some(0.016),
        ..Default::default()
    });
    // Smoothing length: the root spacing of Mannequin A is ~1.8 mm and its segments 11 mm, so
    // 6 mm reaches a few neighbouring strands (about 10 neighbours a node on the head); the
    // repulsion and viscosity within the paper's ranges ([0, 0.5], [0, 200]).
    scene.hair_hair = Some(crate::scene::HairHairSpec {
        smoothing_length: Some(0.0045),
        rest_density: Some(2.0),
        stiffness: Some(0.2),
        viscosity: Some(20.0),
        max_neighbours: Some(24),
        skip_same_strand: Some(3),
    });
    // The head turns to one side and back over two seconds.
    scene.head = Some(HeadSpec {
        motion: Some(MotionSpec::Keyframes(KeyframesSpec {
            keys: [(0.0, 0.0), (0.5, 0.8), (1.5, -0.8), (2.0, 0.0)]
                .iter()
                .map(|&(time, angle)| crate::scene::KeySpec {
                    time,
                    position: None,
                    axis: Some([0.0, 1.0, 0.0]),
                    angle: Some(angle),
                })
                .collect(),
        })),
    });
    scene.colliders = vec![
        sphere([0.0, 0.0, 0.0], 0.1),
        capsule([0.0, -0.08, 0.0], [0.0, -0.2, 0.0], 0.05),
        capsule([-0.2, -0.24, 0.0], [0.2, -0.24, 0.0], 0.07),
        capsule([0.0, -0.25, 0.0], [0.0, -0.6, 0.0], 0.15),
    ];
    scene.hair = Some(HairSpec::Scalp(ScalpSpec {
        leaders,
        nodes,
        length: 0.25,
        centre: None,
        radius: Some(0.1),
        cap_angle: Some(1.3),
        followers: None,
        style: None,
    }));
    scene
}

fn haptic() -> Scene {
    let mut effects = ROD_EFFECTS.to_vec();
    effects.push("grabs");
    let mut scene = base("haptic", about("haptic"), "rod", 0.001, 2000, &effects);
    scene.drag = Some(2.0e-7);
    let (nodes, length, grabbed) = (30u32, 0.3f32, 24u32);
    scene.strands = vec![StrandSpec {
        root: Some([0.0, 0.0, 0.0]),
        direction: Some([0.0, -1.0, 0.0]),
        length: Some(length),
        nodes: Some(nodes),
        ..StrandSpec::default()
    }];
    // The grab starts where the node rests, so nothing jumps at the first step.
    let rest = generate::strand(
        hairsim_core::Vec3::ZERO,
        -hairsim_core::Vec3::Y,
        f64::from(length),
        nodes as usize,
        Style::Straight,
    );
    let start = rest[grabbed as usize].to_array();
    let side = [start[0] + 0.08, start[1] + 0.03, start[2]];
    scene.grabs = vec![GrabSpec {
        strand: 0,
        node: grabbed,
        force_limit: 0.05,
        coupling: None,
        path: Some(vec![
            PathKey {
                time: 0.0,
                target: start,
            },
            PathKey {
                time: 1.0,
                target: side,
            },
            PathKey {
                time: 2.0,
                target: start,
            },
        ]),
        circle: None,
        release: None,
    }];
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_is_named_as_listed_and_round_trips_through_toml() {
        for b in BUILTINS {
            let scene = (b.scene)();
            assert_eq!(scene.name, b.name);
            let text = scene.to_toml();
            let back = Scene::from_toml(&text, b.name).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(back, scene, "{}", b.name);
        }
    }
}
