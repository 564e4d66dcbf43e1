//! `tests/firmware_scene_data.h`: the scene `hairsim_core::scenes::firmware` as data for the C
//! functions, every float an exact C99 hex literal, read from the scene the core builds. The
//! test `scene_header_is_current` fails when the file differs from what the scene gives now;
//! `HAIRSIM_BLESS=1 cargo test` rewrites it.

use std::fmt::Write as _;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use hairsim_core::scenes::firmware;
use hairsim_core::{Collider, DefaultMath, Material, Shake, Shape, World};

use crate::convert;
use crate::types::*;

/// Where the header lives, from the crate's folder.
pub(crate) const PATH: &str = "tests/firmware_scene_data.h";

/// The scene's radius and frequency of the grab's circle (`firmware::grab_target`: a 1 cm
/// circle at 2 Hz); `firmware_scene_helpers_give_the_scene_bits` checks them bit for bit.
const GRAB_CIRCLE_RADIUS: f32 = 0.01;
const GRAB_CIRCLE_FREQUENCY: f32 = 2.0;

/// The firmware scene as the C functions take it.
pub(crate) struct Scene {
    pub params: hairsim_params,
    pub material: hairsim_material,
    pub colliders: Vec<hairsim_collider>,
    pub strands: Vec<Vec<hairsim_vec3>>,
    pub grabs: Vec<hairsim_grab>,
    pub circles: Vec<hairsim_circle>,
    pub shake: hairsim_shake,
}

fn collider_to_c(c: &Collider) -> hairsim_collider {
    let zero = hairsim_vec3::default();
    let (shape, a, b, radius) = match c.shape {
        Shape::Sphere { centre, radius } => (hairsim_shape::Sphere, centre, None, radius),
        Shape::Capsule { a, b, radius } => (hairsim_shape::Capsule, a, Some(b), radius),
        Shape::Plane { point, normal } => (hairsim_shape::Plane, point, Some(normal), 0.0),
    };
    hairsim_collider {
        shape: shape as u32,
        attached_to_head: u32::from(c.attached_to_head),
        a: convert::vec3_to_c(a),
        b: b.map_or(zero, convert::vec3_to_c),
        radius,
    }
}

impl Scene {
    /// Reads the scene from the world `firmware::build` makes.
    pub(crate) fn firmware() -> Scene {
        let mut world: std::boxed::Box<
            World<{ firmware::STRANDS }, { firmware::NODES }, DefaultMath>,
        > = std::boxed::Box::default();
        firmware::build(&mut world).expect("the firmware scene builds");
        let shake = Shake::TEN_RAD_PER_S;
        Scene {
            params: convert::params_to_c(world.params()),
            // `firmware::build` gives every strand a human hair.
            material: convert::material_to_c(&Material::HUMAN_HAIR),
            colliders: world.colliders().iter().map(collider_to_c).collect(),
            strands: world
                .strands()
                .iter()
                .map(|s| {
                    s.positions()
                        .iter()
                        .map(|p| convert::vec3_to_c(*p))
                        .collect()
                })
                .collect(),
            grabs: world
                .grabs()
                .iter()
                .map(|g| hairsim_grab {
                    strand: g.strand,
                    node: g.node,
                    target: convert::vec3_to_c(g.target),
                    force_limit: g.force_limit,
                    stiffness: g.coupling.map_or(0.0, |c| c.stiffness),
                    damping: g.coupling.map_or(0.0, |c| c.damping),
                })
                .collect(),
            circles: world
                .grabs()
                .iter()
                .map(|g| hairsim_circle {
                    start: convert::vec3_to_c(g.target),
                    radius: GRAB_CIRCLE_RADIUS,
                    frequency: GRAB_CIRCLE_FREQUENCY,
                })
                .collect(),
            shake: hairsim_shake {
                axis: convert::vec3_to_c(shake.axis),
                centre: convert::vec3_to_c(shake.centre),
                amplitude: shake.amplitude,
                frequency: shake.frequency,
            },
        }
    }
}

/// `v` as an exact C99 hexadecimal float literal: `0x1.0624dep-10f` for 0.001.
pub(crate) fn hex(v: f32) -> String {
    assert!(v.is_finite(), "{v} has no C literal");
    let bits = v.to_bits();
    let sign = if bits >> 31 == 1 { "-" } else { "" };
    let exponent = ((bits >> 23) & 0xff) as i32;
    let mantissa = bits & 0x7f_ffff;
    if exponent == 0 && mantissa == 0 {
        return format!("{sign}0x0p+0f");
    }
    // Subnormals: 0x0.<mantissa>p-126.
    let (lead, power) = if exponent == 0 {
        (0, -126)
    } else {
        (1, exponent - 127)
    };
    // 23 mantissa bits, shifted to 24, are 6 hex digits.
    let mut digits = format!("{:06x}", mantissa << 1);
    while digits.ends_with('0') {
        digits.pop();
    }
    if digits.is_empty() {
        format!("{sign}0x{lead}p{power:+}f")
    } else {
        format!("{sign}0x{lead}.{digits}p{power:+}f")
    }
}

fn vec3(v: hairsim_vec3) -> String {
    format!("{{{}, {}, {}}}", hex(v.x), hex(v.y), hex(v.z))
}

/// A scalar with its decimal value as a comment.
fn scalar(v: f32) -> String {
    format!("{} /* {v:?} */", hex(v))
}

fn names(value: u32, table: &[(u32, &str)]) -> String {
    let names: Vec<&str> = table
        .iter()
        .filter(|(bit, _)| value & bit != 0)
        .map(|(_, name)| *name)
        .collect();
    assert_eq!(
        table
            .iter()
            .filter(|(bit, _)| value & bit != 0)
            .fold(0, |all, (bit, _)| all | bit),
        value,
        "every bit has a name"
    );
    if names.is_empty() {
        "0".into()
    } else {
        names.join(" | ")
    }
}

fn name(value: u32, table: &[(u32, &'static str)]) -> &'static str {
    table
        .iter()
        .find(|(v, _)| *v == value)
        .map(|(_, n)| *n)
        .expect("a named value")
}

const EFFECT_NAMES: [(u32, &str); 10] = [
    (HAIRSIM_EFFECT_GRAVITY, "HAIRSIM_EFFECT_GRAVITY"),
    (HAIRSIM_EFFECT_DRAG, "HAIRSIM_EFFECT_DRAG"),
    (HAIRSIM_EFFECT_BENDING, "HAIRSIM_EFFECT_BENDING"),
    (HAIRSIM_EFFECT_TWIST, "HAIRSIM_EFFECT_TWIST"),
    (
        HAIRSIM_EFFECT_INEXTENSIBILITY,
        "HAIRSIM_EFFECT_INEXTENSIBILITY",
    ),
    (HAIRSIM_EFFECT_COLLISIONS, "HAIRSIM_EFFECT_COLLISIONS"),
    (HAIRSIM_EFFECT_SHAPE, "HAIRSIM_EFFECT_SHAPE"),
    (HAIRSIM_EFFECT_WIND, "HAIRSIM_EFFECT_WIND"),
    (HAIRSIM_EFFECT_GRABS, "HAIRSIM_EFFECT_GRABS"),
    (HAIRSIM_EFFECT_HAIR_HAIR, "HAIRSIM_EFFECT_HAIR_HAIR"),
];
const SOLVER_NAMES: [(u32, &str); 2] = [
    (hairsim_solver::Rod as u32, "HAIRSIM_SOLVER_ROD"),
    (hairsim_solver::Dftl as u32, "HAIRSIM_SOLVER_DFTL"),
];
const MODE_NAMES: [(u32, &str); 2] = [
    (hairsim_mode::Converge as u32, "HAIRSIM_MODE_CONVERGE"),
    (hairsim_mode::FixedCost as u32, "HAIRSIM_MODE_FIXED_COST"),
];
const TWIST_NAMES: [(u32, &str); 2] = [
    (
        hairsim_twist::HairOptimised as u32,
        "HAIRSIM_TWIST_HAIR_OPTIMISED",
    ),
    (hairsim_twist::Newton as u32, "HAIRSIM_TWIST_NEWTON"),
];
const SHAPE_NAMES: [(u32, &str); 3] = [
    (hairsim_shape::Sphere as u32, "HAIRSIM_SHAPE_SPHERE"),
    (hairsim_shape::Capsule as u32, "HAIRSIM_SHAPE_CAPSULE"),
    (hairsim_shape::Plane as u32, "HAIRSIM_SHAPE_PLANE"),
];

/// The header's text.
pub(crate) fn generate(scene: &Scene) -> String {
    let p = &scene.params;
    let m = &scene.material;
    let mut h = String::new();
    let w = &mut h;
    let max_points = scene.strands.iter().map(Vec::len).max().unwrap_or(0);
    writeln!(
        w,
        "/*\n * The scene `firmware` of hairsim_core::scenes (the world `hairsim run firmware` \
         steps) as\n * data for the C functions: every float an exact C99 hex literal read from \
         the world the\n * core builds. Generated by a unit test of ffi/ (src/scene_header.rs; \
         `HAIRSIM_BLESS=1\n * cargo test` in ffi/ rewrites it): do not edit. Included by \
         firmware_scene.c only.\n */\n\
         #ifndef HAIRSIM_FIRMWARE_SCENE_DATA_H\n#define HAIRSIM_FIRMWARE_SCENE_DATA_H\n\n\
         #include \"hairsim.h\"\n"
    )
    .unwrap();
    writeln!(w, "#define FIRMWARE_STEPS {}", firmware::STEPS).unwrap();
    writeln!(w, "#define FIRMWARE_STRANDS {}", scene.strands.len()).unwrap();
    writeln!(w, "#define FIRMWARE_MAX_POINTS {max_points}").unwrap();
    writeln!(w, "#define FIRMWARE_COLLIDERS {}", scene.colliders.len()).unwrap();
    writeln!(w, "#define FIRMWARE_GRABS {}\n", scene.grabs.len()).unwrap();
    writeln!(w, "static const hairsim_params FIRMWARE_PARAMS = {{").unwrap();
    let fields: [(&str, String); 22] = [
        ("solver", name(p.solver, &SOLVER_NAMES).into()),
        ("dt", scalar(p.dt)),
        ("effects", names(p.effects, &EFFECT_NAMES)),
        ("mode", name(p.mode, &MODE_NAMES).into()),
        ("gravity", vec3(p.gravity)),
        ("drag", scalar(p.drag)),
        (
            "rod_projection_iterations",
            format!("{}", p.rod_projection_iterations),
        ),
        (
            "rod_projection_tolerance",
            scalar(p.rod_projection_tolerance),
        ),
        ("rod_twist", name(p.rod_twist, &TWIST_NAMES).into()),
        (
            "rod_newton_iterations",
            format!("{}", p.rod_newton_iterations),
        ),
        ("rod_newton_tolerance", scalar(p.rod_newton_tolerance)),
        ("dftl_damping", scalar(p.dftl_damping)),
        ("dftl_global_shape", scalar(p.dftl_global_shape)),
        ("dftl_local_shape", scalar(p.dftl_local_shape)),
        ("dftl_reference_dt", scalar(p.dftl_reference_dt)),
        ("dftl_global_shape_fade", scalar(p.dftl_global_shape_fade)),
        ("dftl_local_shape_fade", scalar(p.dftl_local_shape_fade)),
        ("wind_direction", vec3(p.wind_direction)),
        ("wind_strength", scalar(p.wind_strength)),
        ("wind_gust", scalar(p.wind_gust)),
        ("wind_gust_frequency", scalar(p.wind_gust_frequency)),
        ("wind_seed", format!("0x{:08x}u", p.wind_seed)),
    ];
    for (field, value) in &fields {
        writeln!(w, "    .{field} = {value},").unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    writeln!(w, "static const hairsim_material FIRMWARE_MATERIAL = {{").unwrap();
    for (field, value) in [
        ("youngs_modulus", m.youngs_modulus),
        ("shear_modulus", m.shear_modulus),
        ("radius", m.radius),
        ("density", m.density),
        ("minor_axis_penalty", m.minor_axis_penalty),
    ] {
        writeln!(w, "    .{field} = {},", scalar(value)).unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    writeln!(
        w,
        "static const hairsim_collider FIRMWARE_COLLIDER[FIRMWARE_COLLIDERS] = {{"
    )
    .unwrap();
    for c in &scene.colliders {
        writeln!(
            w,
            "    {{.shape = {}, .attached_to_head = {}, .a = {}, .b = {}, .radius = {}}},",
            name(c.shape, &SHAPE_NAMES),
            c.attached_to_head,
            vec3(c.a),
            vec3(c.b),
            scalar(c.radius)
        )
        .unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    writeln!(
        w,
        "/* Strand s is the polyline FIRMWARE_POINT[s][0 .. FIRMWARE_POINT_COUNT[s]). */"
    )
    .unwrap();
    let counts: Vec<String> = scene.strands.iter().map(|s| s.len().to_string()).collect();
    writeln!(
        w,
        "static const size_t FIRMWARE_POINT_COUNT[FIRMWARE_STRANDS] = {{{}}};",
        counts.join(", ")
    )
    .unwrap();
    writeln!(
        w,
        "static const hairsim_vec3 FIRMWARE_POINT[FIRMWARE_STRANDS][FIRMWARE_MAX_POINTS] = {{"
    )
    .unwrap();
    for points in &scene.strands {
        writeln!(w, "    {{").unwrap();
        for p in points {
            writeln!(w, "        {},", vec3(*p)).unwrap();
        }
        writeln!(w, "    }},").unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    writeln!(
        w,
        "static const hairsim_grab FIRMWARE_GRAB[FIRMWARE_GRABS] = {{"
    )
    .unwrap();
    for g in &scene.grabs {
        // A prescribed grab leaves the coupling's fields at their zero.
        let coupling = if g.stiffness == 0.0 && g.damping == 0.0 {
            String::new()
        } else {
            format!(
                ", .stiffness = {}, .damping = {}",
                scalar(g.stiffness),
                scalar(g.damping)
            )
        };
        writeln!(
            w,
            "    {{.strand = {}, .node = {}, .target = {}, .force_limit = {}{coupling}}},",
            g.strand,
            g.node,
            vec3(g.target),
            scalar(g.force_limit)
        )
        .unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    writeln!(
        w,
        "/* Grab g's target before step k (0-based): hairsim_circle_target(&FIRMWARE_GRAB_CIRCLE[g], t)\n \
         * with t = (float)(k + 1) * FIRMWARE_PARAMS.dt. */"
    )
    .unwrap();
    writeln!(
        w,
        "static const hairsim_circle FIRMWARE_GRAB_CIRCLE[FIRMWARE_GRABS] = {{"
    )
    .unwrap();
    for c in &scene.circles {
        writeln!(
            w,
            "    {{.start = {}, .radius = {}, .frequency = {}}},",
            vec3(c.start),
            scalar(c.radius),
            scalar(c.frequency)
        )
        .unwrap();
    }
    writeln!(w, "}};\n").unwrap();
    let s = &scene.shake;
    writeln!(
        w,
        "/* The head's pose of step k: hairsim_shake_pose(&FIRMWARE_SHAKE, t), t as above. */\n\
         static const hairsim_shake FIRMWARE_SHAKE = {{\n    .axis = {},\n    .centre = {},\n    \
         .amplitude = {},\n    .frequency = {},\n}};\n\n#endif /* HAIRSIM_FIRMWARE_SCENE_DATA_H */",
        vec3(s.axis),
        vec3(s.centre),
        scalar(s.amplitude),
        scalar(s.frequency)
    )
    .unwrap();
    h
}
