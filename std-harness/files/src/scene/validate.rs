//! Every check a scene passes before anything is built: format, names, ranges, and which
//! fields go together. Each failure names its field and says what is allowed.

use hairsim_core::params::{MAX_DT, MIN_DT};
use hairsim_core::strand::MATERIAL_RANGES;
use hairsim_core::{Coupling, Effect, Solver};

use super::error::FieldError;
use super::{
    ColliderSpec, GrabSpec, HairHairSpec, HairSpec, MaterialSpec, MotionSpec, OutputSpec, Scene,
    StrandSpec, StyleSpec, WindSpec, FORMAT, V3,
};

/// Largest node count of one strand (the largest capacity this build monomorphises).
pub const MAX_NODES: u32 = 128;
/// Largest coordinate magnitude anywhere in a scene, m.
pub const MAX_COORDINATE: f32 = 100.0;
/// Most strands a scene may generate (leaders; followers are counted apart).
pub const MAX_STRANDS: u32 = 1_000_000;
/// Most steps a run may take.
pub const MAX_STEPS: u64 = 100_000_000;

type Check = Result<(), FieldError>;

fn fail(field: impl Into<String>, message: impl Into<String>) -> Check {
    Err(FieldError::new(field, message))
}

/// `lo ≤ v ≤ hi` and finite.
pub fn range(field: &str, v: f32, lo: f32, hi: f32, unit: &str) -> Check {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        fail(
            field,
            format!("{v} is out of range, allowed {lo} to {hi}{unit}"),
        )
    }
}

/// `lo < v ≤ hi` and finite.
pub fn positive(field: &str, v: f32, hi: f32, unit: &str) -> Check {
    if v.is_finite() && v > 0.0 && v <= hi {
        Ok(())
    } else {
        fail(
            field,
            format!("{v} is out of range, allowed > 0 and <= {hi}{unit}"),
        )
    }
}

/// An integer in `lo..=hi`.
pub fn count(field: &str, v: u64, lo: u64, hi: u64) -> Check {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        fail(field, format!("{v} is out of range, allowed {lo} to {hi}"))
    }
}

/// A point: finite, every coordinate within ±`MAX_COORDINATE`.
pub fn point(field: &str, p: V3) -> Check {
    if p.iter().all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE) {
        Ok(())
    } else {
        fail(
            field,
            format!(
                "{p:?} is out of range, allowed finite coordinates within +-{MAX_COORDINATE} m"
            ),
        )
    }
}

/// A direction: finite and not zero (it is normalised).
pub fn direction(field: &str, d: V3) -> Check {
    let length2: f32 = d.iter().map(|c| c * c).sum();
    if d.iter().all(|c| c.is_finite()) && length2 > 1e-12 && length2.is_finite() {
        Ok(())
    } else {
        fail(
            field,
            format!("{d:?} is not a direction, allowed any finite non-zero vector"),
        )
    }
}

fn one_of(field: &str, value: &str, allowed: &[&str]) -> Check {
    if allowed.contains(&value) {
        Ok(())
    } else {
        fail(
            field,
            format!("\"{value}\" is not known, allowed {}", quoted(allowed)),
        )
    }
}

fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The solver named in the scene.
pub fn solver(scene: &Scene) -> Result<Solver, FieldError> {
    match scene.solver.as_str() {
        "rod" => Ok(Solver::Rod),
        "dftl" => Ok(Solver::Dftl),
        other => Err(FieldError::new(
            "solver",
            format!("\"{other}\" is not known, allowed \"rod\" or \"dftl\""),
        )),
    }
}

/// The effects named in the scene, checked against the solver.
pub fn effects(scene: &Scene, solver: Solver) -> Result<Vec<Effect>, FieldError> {
    let names: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
    let mut list = Vec::new();
    for (i, name) in scene.effects.iter().enumerate() {
        let field = format!("effects[{i}]");
        let Some(effect) = Effect::from_name(name) else {
            return Err(FieldError::new(
                field,
                format!("\"{name}\" is not an effect, allowed {}", quoted(&names)),
            ));
        };
        if list.contains(&effect) {
            return Err(FieldError::new(
                field,
                format!("\"{name}\" is listed twice, allowed each effect once"),
            ));
        }
        if !solver.supports(effect) {
            return Err(FieldError::new(
                field,
                format!(
                    "the {} solver cannot do \"{name}\", allowed with it: {}",
                    solver.name(),
                    quoted(
                        &Effect::ALL
                            .iter()
                            .filter(|e| solver.supports(**e))
                            .map(|e| e.name())
                            .collect::<Vec<_>>()
                    )
                ),
            ));
        }
        list.push(effect);
    }
    Ok(list)
}

/// Checks the whole scene (everything that does not need the generated strands).
pub fn check(scene: &Scene) -> Check {
    if scene.format != FORMAT {
        return fail(
            "format",
            format!(
                "format {} is not readable by this build, allowed format = {FORMAT} only",
                scene.format
            ),
        );
    }
    name(&scene.name)?;
    if let Some(about) = &scene.about {
        if about.len() > 200 || about.contains('\n') {
            return fail(
                "about",
                "too long, allowed one line of at most 200 characters",
            );
        }
    }
    let solver = solver(scene)?;
    range("dt", scene.dt, MIN_DT, MAX_DT, " s")?;
    match (scene.steps, scene.duration) {
        (Some(_), Some(_)) => {
            return fail(
                "duration",
                "both steps and duration are given, allowed one of them",
            )
        }
        (None, None) => return fail("steps", "missing: give steps (a count) or duration (s)"),
        (Some(steps), None) => count("steps", steps, 1, MAX_STEPS)?,
        (None, Some(duration)) => {
            positive("duration", duration, 36_000.0, " s")?;
            let steps = (f64::from(duration) / f64::from(scene.dt)).round();
            if steps < 1.0 || steps > MAX_STEPS as f64 {
                return fail(
                    "duration",
                    format!("{duration} s is {steps} steps of dt, allowed 1 to {MAX_STEPS} steps"),
                );
            }
        }
    }
    let effects = effects(scene, solver)?;
    if let Some(mode) = &scene.mode {
        one_of("mode", mode, &["converge", "fixed-cost"])?;
    }
    if let Some(g) = scene.gravity {
        point("gravity", g)?;
    }
    if let Some(drag) = scene.drag {
        range("drag", drag, 0.0, 0.01, " kg/s")?;
    } else if effects.contains(&Effect::Drag) {
        return fail(
            "drag",
            "missing: the effect \"drag\" is on, give drag (kg/s per node, 0 to 0.01)",
        );
    }
    if let Some(block) = scene.strands_per_block {
        count("strands_per_block", u64::from(block), 1, 65_536)?;
    }
    if let Some(material) = &scene.material {
        self::material("material", material)?;
    }
    rod(scene)?;
    dftl(scene)?;
    motion(scene)?;
    colliders(&scene.colliders)?;
    if effects.contains(&Effect::Collisions) && scene.colliders.is_empty() {
        return fail(
            "effects",
            "\"collisions\" is on but there is no collider, allowed only with [[colliders]]",
        );
    }
    hair(scene)?;
    for (i, strand) in scene.strands.iter().enumerate() {
        self::strand(&format!("strands[{i}]"), strand)?;
    }
    if scene.hair.is_none() && scene.strands.is_empty() {
        return fail(
            "hair",
            "the scene has no strands, allowed: [hair.stand], [hair.scalp], [hair.file] or [[strands]]",
        );
    }
    grabs(&scene.grabs)?;
    if effects.contains(&Effect::Grabs) && scene.grabs.is_empty() {
        return fail(
            "effects",
            "\"grabs\" is on but there is no grab, allowed only with [[grabs]]",
        );
    }
    match &scene.wind {
        Some(w) => wind(w)?,
        None if effects.contains(&Effect::Wind) => {
            return fail(
                "wind",
                "missing: the effect \"wind\" is on, give a [wind] table",
            );
        }
        None => {}
    }
    if let Some(h) = &scene.hair_hair {
        hair_hair(h)?;
    }
    if let Some(output) = &scene.output {
        self::output(output)?;
    }
    Ok(())
}

fn name(name: &str) -> Check {
    let ok = !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if ok {
        Ok(())
    } else {
        fail(
            "name",
            format!(
                "\"{name}\" is not a scene name, allowed 1 to 64 characters of A-Z a-z 0-9 - _ ."
            ),
        )
    }
}

/// Checks a material (or a strand's override).
pub fn material(prefix: &str, m: &MaterialSpec) -> Check {
    let f = |name: &str| format!("{prefix}.{name}");
    // The core's ranges (`Material::validate`), in their order.
    let given = [
        m.youngs_modulus,
        m.shear_modulus,
        m.radius,
        m.density,
        m.minor_axis_penalty,
    ];
    for (v, r) in given.into_iter().zip(&MATERIAL_RANGES) {
        match v {
            Some(v) if !(v.is_finite() && (r.least..=r.most).contains(&v)) => {
                return fail(
                    f(r.field),
                    format!("{v} is out of range, allowed {}", r.allowed),
                );
            }
            _ => {}
        }
    }
    if let Some(v) = m.tip_stiffness {
        range(
            &f("tip_stiffness"),
            v,
            0.0,
            1.0,
            " (fraction of the root's)",
        )?;
    }
    Ok(())
}

fn rod(scene: &Scene) -> Check {
    let Some(rod) = &scene.rod else { return Ok(()) };
    if let Some(twist) = &rod.twist {
        one_of("rod.twist", twist, &["hair-optimised", "newton"])?;
    }
    if let Some(n) = rod.projection_iterations {
        count("rod.projection_iterations", u64::from(n), 1, 1000)?;
    }
    if let Some(t) = rod.projection_tolerance {
        positive("rod.projection_tolerance", t, 1.0, "")?;
    }
    if let Some(n) = rod.newton_iterations {
        count("rod.newton_iterations", u64::from(n), 1, 100)?;
    }
    if let Some(t) = rod.newton_tolerance {
        positive("rod.newton_tolerance", t, 1.0, " rad")?;
    }
    Ok(())
}

fn dftl(scene: &Scene) -> Check {
    let Some(d) = &scene.dftl else { return Ok(()) };
    if let Some(v) = d.damping {
        range("dftl.damping", v, 0.0, 1.0, "")?;
    }
    if let Some(v) = d.global_shape {
        range(
            "dftl.global_shape",
            v,
            0.0,
            1.0,
            " (per step at reference_dt)",
        )?;
    }
    if let Some(v) = d.local_shape {
        range(
            "dftl.local_shape",
            v,
            0.0,
            1.0,
            " (per step at reference_dt)",
        )?;
    }
    if let Some(v) = d.reference_dt {
        positive("dftl.reference_dt", v, 1.0, " s")?;
    }
    if let Some(v) = d.global_shape_fade {
        range(
            "dftl.global_shape_fade",
            v,
            0.0,
            1.0,
            " (1: zero at the tip)",
        )?;
    }
    if let Some(v) = d.local_shape_fade {
        range(
            "dftl.local_shape_fade",
            v,
            0.0,
            1.0,
            " (1: zero at the tip)",
        )?;
    }
    Ok(())
}

fn motion(scene: &Scene) -> Check {
    let Some(motion) = scene.head.as_ref().and_then(|h| h.motion.as_ref()) else {
        return Ok(());
    };
    match motion {
        MotionSpec::Still => Ok(()),
        MotionSpec::Shake(s) => {
            let f = "head.motion.shake";
            direction(&format!("{f}.axis"), s.axis)?;
            if let Some(c) = s.centre {
                point(&format!("{f}.centre"), c)?;
            }
            range(
                &format!("{f}.amplitude"),
                s.amplitude,
                0.0,
                std::f32::consts::PI,
                " rad",
            )?;
            match (s.frequency, s.peak_speed) {
                (Some(_), Some(_)) => fail(
                    format!("{f}.peak_speed"),
                    "both frequency and peak_speed are given, allowed one of them",
                ),
                (None, None) => fail(
                    format!("{f}.frequency"),
                    "missing: give frequency (Hz) or peak_speed (rad/s)",
                ),
                (Some(hz), None) => range(&format!("{f}.frequency"), hz, 0.0, 100.0, " Hz"),
                (None, Some(w)) => {
                    range(&format!("{f}.peak_speed"), w, 0.0, 1000.0, " rad/s")?;
                    if w > 0.0 && s.amplitude <= 0.0 {
                        return fail(
                            format!("{f}.amplitude"),
                            "is 0 with a peak_speed, allowed > 0 when peak_speed is given",
                        );
                    }
                    Ok(())
                }
            }
        }
        MotionSpec::Keyframes(k) => {
            let f = "head.motion.keyframes.keys";
            if k.keys.is_empty() || k.keys.len() > 100_000 {
                return fail(f, "allowed 1 to 100000 keys");
            }
            let mut previous = None;
            for (i, key) in k.keys.iter().enumerate() {
                let kf = format!("{f}[{i}]");
                range(&format!("{kf}.time"), key.time, 0.0, 36_000.0, " s")?;
                if i == 0 && key.time != 0.0 {
                    return fail(
                        format!("{kf}.time"),
                        format!("{} s, allowed: the first key at time 0", key.time),
                    );
                }
                if let Some(p) = previous {
                    if key.time <= p {
                        return fail(
                            format!("{kf}.time"),
                            format!("{} s is not after the previous key ({p} s), allowed increasing times", key.time),
                        );
                    }
                }
                previous = Some(key.time);
                if let Some(p) = key.position {
                    point(&format!("{kf}.position"), p)?;
                }
                if let Some(a) = key.axis {
                    direction(&format!("{kf}.axis"), a)?;
                }
                if let Some(a) = key.angle {
                    range(
                        &format!("{kf}.angle"),
                        a,
                        -std::f32::consts::TAU,
                        std::f32::consts::TAU,
                        " rad",
                    )?;
                }
            }
            Ok(())
        }
    }
}

fn colliders(list: &[ColliderSpec]) -> Check {
    let cap = hairsim_core::collide::MAX_COLLIDERS;
    if list.len() > cap {
        return fail(
            format!("colliders[{cap}]"),
            format!("{} colliders, allowed at most {cap}", list.len()),
        );
    }
    for (i, c) in list.iter().enumerate() {
        collider(&format!("colliders[{i}]"), c)?;
    }
    Ok(())
}

fn collider(f: &str, c: &ColliderSpec) -> Check {
    one_of(
        &format!("{f}.shape"),
        &c.shape,
        &["sphere", "capsule", "plane"],
    )?;
    let given: [(&str, bool); 6] = [
        ("centre", c.centre.is_some()),
        ("radius", c.radius.is_some()),
        ("a", c.a.is_some()),
        ("b", c.b.is_some()),
        ("point", c.point.is_some()),
        ("normal", c.normal.is_some()),
    ];
    let needs: &[&str] = match c.shape.as_str() {
        "sphere" => &["centre", "radius"],
        "capsule" => &["a", "b", "radius"],
        _ => &["point", "normal"],
    };
    for (field, is_given) in given {
        if is_given && !needs.contains(&field) {
            return fail(
                format!("{f}.{field}"),
                format!("not a field of a {}, allowed {}", c.shape, quoted(needs)),
            );
        }
        if !is_given && needs.contains(&field) {
            return fail(
                format!("{f}.{field}"),
                format!("missing: a {} needs {}", c.shape, quoted(needs)),
            );
        }
    }
    for (field, p) in [
        ("centre", c.centre),
        ("a", c.a),
        ("b", c.b),
        ("point", c.point),
    ] {
        if let Some(p) = p {
            point(&format!("{f}.{field}"), p)?;
        }
    }
    if let Some(r) = c.radius {
        positive(&format!("{f}.radius"), r, 10.0, " m")?;
    }
    if let Some(n) = c.normal {
        direction(&format!("{f}.normal"), n)?;
    }
    Ok(())
}

/// Checks a style; `f` is the prefix of its fields.
pub fn style(f: &str, s: &StyleSpec) -> Check {
    let shape = s.shape.as_deref().unwrap_or("straight");
    one_of(&format!("{f}shape"), shape, &["straight", "wavy", "curly"])?;
    let needs: &[&str] = match shape {
        "straight" => &[],
        "wavy" => &["amplitude", "period"],
        _ => &["radius", "period"],
    };
    for (field, value) in [
        ("amplitude", s.amplitude),
        ("period", s.period),
        ("radius", s.radius),
    ] {
        let path = format!("{f}{field}");
        match value {
            Some(_) if !needs.contains(&field) => {
                return fail(
                    path,
                    format!(
                        "not used by shape \"{shape}\", allowed with it: {}",
                        if needs.is_empty() {
                            "none".into()
                        } else {
                            quoted(needs)
                        }
                    ),
                );
            }
            None if needs.contains(&field) => {
                return fail(
                    path,
                    format!("missing: shape \"{shape}\" needs {}", quoted(needs)),
                );
            }
            Some(v) => positive(&path, v, 1.0, " m")?,
            None => {}
        }
    }
    Ok(())
}

fn generated(f: &str, nodes: u32, length: f32) -> Check {
    count(
        &format!("{f}.nodes"),
        u64::from(nodes),
        3,
        u64::from(MAX_NODES),
    )?;
    positive(&format!("{f}.length"), length, 10.0, " m")
}

fn hair(scene: &Scene) -> Check {
    match &scene.hair {
        None => Ok(()),
        Some(HairSpec::Stand(s)) => {
            let f = "hair.stand";
            count(
                &format!("{f}.wisps"),
                u64::from(s.wisps),
                1,
                u64::from(MAX_STRANDS),
            )?;
            generated(f, s.nodes, s.length)?;
            if let Some(v) = s.spacing {
                positive(&format!("{f}.spacing"), v, 10.0, " m")?;
            }
            if let Some(p) = s.origin {
                point(&format!("{f}.origin"), p)?;
            }
            if let Some(d) = s.direction {
                direction(&format!("{f}.direction"), d)?;
            }
            if let Some(n) = s.followers {
                count(&format!("{f}.followers"), u64::from(n), 0, 10_000)?;
            }
            if let Some(st) = &s.style {
                style(&format!("{f}.style."), st)?;
            }
            Ok(())
        }
        Some(HairSpec::Scalp(s)) => {
            let f = "hair.scalp";
            count(
                &format!("{f}.leaders"),
                u64::from(s.leaders),
                1,
                u64::from(MAX_STRANDS),
            )?;
            generated(f, s.nodes, s.length)?;
            if let Some(p) = s.centre {
                point(&format!("{f}.centre"), p)?;
            }
            if let Some(r) = s.radius {
                positive(&format!("{f}.radius"), r, 10.0, " m")?;
            }
            if let Some(a) = s.cap_angle {
                positive(&format!("{f}.cap_angle"), a, std::f32::consts::PI, " rad")?;
            }
            if let Some(n) = s.followers {
                count(&format!("{f}.followers"), u64::from(n), 0, 10_000_000)?;
            }
            if let Some(st) = &s.style {
                style(&format!("{f}.style."), st)?;
            }
            Ok(())
        }
        Some(HairSpec::File(file)) => {
            let f = "hair.file";
            if file.path.is_empty() {
                return fail(
                    format!("{f}.path"),
                    "empty, allowed the path of a hair file",
                );
            }
            if !crate::hairfile::is_hair_file(&file.path) {
                return fail(
                    format!("{f}.path"),
                    format!(
                        "\"{}\" is not a hair file, allowed a .hair, .tfx, .obj, .ply or .usda \
                         file",
                        file.path
                    ),
                );
            }
            if let Some(s) = file.scale {
                positive(&format!("{f}.scale"), s, 1.0e3, "")?;
            }
            if let Some(up) = &file.up {
                one_of(&format!("{f}.up"), up, &["y", "z"])?;
            }
            if let Some(n) = file.nodes {
                count(&format!("{f}.nodes"), u64::from(n), 3, u64::from(MAX_NODES))?;
            }
            if let Some(n) = file.max_strands {
                count(
                    &format!("{f}.max_strands"),
                    u64::from(n),
                    1,
                    u64::from(MAX_STRANDS),
                )?;
            }
            if let Some(l) = file.min_length {
                range(&format!("{f}.min_length"), l, 0.0, 10.0, " m")?;
            }
            Ok(())
        }
    }
}

fn strand(f: &str, s: &StrandSpec) -> Check {
    if let Some(m) = &s.material {
        material(&format!("{f}.material"), m)?;
    }
    let generated_fields = [
        ("root", s.root.is_some()),
        ("direction", s.direction.is_some()),
        ("length", s.length.is_some()),
        ("nodes", s.nodes.is_some()),
        ("shape", s.shape.is_some()),
        ("amplitude", s.amplitude.is_some()),
        ("period", s.period.is_some()),
        ("radius", s.radius.is_some()),
    ];
    if let Some(points) = &s.points {
        if let Some((field, _)) = generated_fields.iter().find(|(_, given)| *given) {
            return fail(
                format!("{f}.{field}"),
                "given with points, allowed either points (an explicit polyline) or root, direction, length, nodes (a generated strand)",
            );
        }
        count(
            &format!("{f}.points"),
            points.len() as u64,
            3,
            u64::from(MAX_NODES),
        )?;
        for (j, p) in points.iter().enumerate() {
            point(&format!("{f}.points[{j}]"), *p)?;
        }
        return Ok(());
    }
    for field in ["root", "direction", "length", "nodes"] {
        if !generated_fields
            .iter()
            .any(|(name, given)| *name == field && *given)
        {
            return fail(
                format!("{f}.{field}"),
                "missing: a generated strand needs root, direction, length and nodes (or give points)",
            );
        }
    }
    point(&format!("{f}.root"), s.root.unwrap_or_default())?;
    direction(&format!("{f}.direction"), s.direction.unwrap_or_default())?;
    generated(f, s.nodes.unwrap_or_default(), s.length.unwrap_or_default())?;
    style(
        &format!("{f}."),
        &StyleSpec {
            shape: s.shape.clone(),
            amplitude: s.amplitude,
            period: s.period,
            radius: s.radius,
        },
    )
}

fn grabs(list: &[GrabSpec]) -> Check {
    let cap = hairsim_core::grab::MAX_GRABS;
    if list.len() > cap {
        return fail(
            format!("grabs[{cap}]"),
            format!("{} grabs, allowed at most {cap}", list.len()),
        );
    }
    for (i, g) in list.iter().enumerate() {
        let f = format!("grabs[{i}]");
        positive(&format!("{f}.force_limit"), g.force_limit, 1000.0, " N")?;
        if let Some(c) = &g.coupling {
            let ((k_low, k_high), (b_low, b_high)) = (Coupling::STIFFNESS, Coupling::DAMPING);
            range(
                &format!("{f}.coupling.stiffness"),
                c.stiffness,
                k_low,
                k_high,
                " N/m",
            )?;
            range(
                &format!("{f}.coupling.damping"),
                c.damping,
                b_low,
                b_high,
                " N·s/m",
            )?;
        }
        match (&g.path, &g.circle) {
            (Some(_), Some(_)) => {
                return fail(
                    format!("{f}.circle"),
                    "both path and circle are given, allowed one of them",
                );
            }
            (None, None) => {
                return fail(format!("{f}.path"), "missing: give path (keys) or circle");
            }
            (None, Some(c)) => {
                point(&format!("{f}.circle.start"), c.start)?;
                positive(&format!("{f}.circle.radius"), c.radius, 10.0, " m")?;
                range(
                    &format!("{f}.circle.frequency"),
                    c.frequency,
                    0.0,
                    100.0,
                    " Hz",
                )?;
                if let Some(u) = c.u {
                    direction(&format!("{f}.circle.u"), u)?;
                }
                if let Some(v) = c.v {
                    direction(&format!("{f}.circle.v"), v)?;
                }
            }
            (Some(path), None) => {
                if path.is_empty() || path.len() > 100_000 {
                    return fail(format!("{f}.path"), "allowed 1 to 100000 keys");
                }
                let mut previous: Option<f32> = None;
                for (k, key) in path.iter().enumerate() {
                    let kf = format!("{f}.path[{k}]");
                    range(&format!("{kf}.time"), key.time, 0.0, 36_000.0, " s")?;
                    if let Some(p) = previous {
                        if key.time <= p {
                            return fail(
                                format!("{kf}.time"),
                                format!(
                                    "{} s is not after the previous key ({p} s), allowed increasing times",
                                    key.time
                                ),
                            );
                        }
                    }
                    previous = Some(key.time);
                    point(&format!("{kf}.target"), key.target)?;
                }
            }
        }
        if let Some(r) = g.release {
            range(&format!("{f}.release"), r, 0.0, 36_000.0, " s")?;
        }
    }
    Ok(())
}

fn wind(w: &WindSpec) -> Check {
    direction("wind.direction", w.direction)?;
    range("wind.strength", w.strength, 0.0, 1000.0, " m/s2")?;
    if let Some(g) = w.gust {
        range("wind.gust", g, 0.0, 10.0, " (fraction of strength)")?;
    }
    if let Some(f) = w.gust_frequency {
        range("wind.gust_frequency", f, 0.0, 1000.0, " Hz")?;
    }
    Ok(())
}

fn hair_hair(h: &HairHairSpec) -> Check {
    if let Some(v) = h.smoothing_length {
        range("hair-hair.smoothing_length", v, 1.0e-4, 1.0, " m")?;
    }
    if let Some(v) = h.rest_density {
        range("hair-hair.rest_density", v, 0.0, 1.0e5, " kg/m3")?;
    }
    if let Some(v) = h.stiffness {
        range("hair-hair.stiffness", v, 0.0, 0.5, " m2/s2")?;
    }
    if let Some(v) = h.viscosity {
        range("hair-hair.viscosity", v, 0.0, 200.0, "")?;
    }
    if let Some(n) = h.max_neighbours {
        count("hair-hair.max_neighbours", u64::from(n), 1, 256)?;
    }
    if let Some(n) = h.skip_same_strand {
        count("hair-hair.skip_same_strand", u64::from(n), 0, 64)?;
    }
    Ok(())
}

fn output(o: &OutputSpec) -> Check {
    if let Some(every) = o.every {
        count("output.every", every, 1, MAX_STEPS)?;
    }
    if let Some(formats) = &o.formats {
        for (i, name) in formats.iter().enumerate() {
            one_of(
                &format!("output.formats[{i}]"),
                name,
                &["obj", "ply", "hair", "usda", "tfx"],
            )?;
        }
    }
    if let Some(p) = &o.picture {
        one_of("output.picture", p, &["png", "gif"])?;
    }
    if let Some(v) = &o.view {
        one_of("output.view", v, &["front", "back", "side", "top"])?;
    }
    if let Some(w) = o.width {
        count("output.width", u64::from(w), 16, 8192)?;
    }
    if let Some(h) = o.height {
        count("output.height", u64::from(h), 16, 8192)?;
    }
    Ok(())
}
