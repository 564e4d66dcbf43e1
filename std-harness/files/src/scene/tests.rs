//! Every scene error, with its line, field and message.

use super::*;

const BASE: &str = r#"format = 1
name = "t"
solver = "rod"
dt = 0.001
steps = 10
effects = ["gravity"]
[[strands]]
root = [0.0, 0.0, 0.0]
direction = [1.0, 0.0, 0.0]
length = 0.1
nodes = 5
"#;

/// The base scene with `replace` applied and `tail` appended (tail starts at line 12).
fn scene(replace: &[(&str, &str)], tail: &str) -> String {
    let mut text = BASE.to_string();
    for (old, new) in replace {
        assert!(text.contains(old), "{old}");
        text = text.replacen(old, new, 1);
    }
    text.push_str(tail);
    text
}

fn error(text: &str) -> String {
    match Scene::parse_and_prepare(text, "t.toml", Path::new(".")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[track_caller]
fn refused(replace: &[(&str, &str)], tail: &str, expected: &str) {
    let text = scene(replace, tail);
    let e = error(&text);
    assert!(
        e.starts_with(expected),
        "\nexpected: {expected}\n     got: {e}\nscene:\n{text}"
    );
}

#[test]
fn the_base_scene_is_valid() {
    let (_, p) = Scene::parse_and_prepare(BASE, "t.toml", Path::new(".")).unwrap();
    assert_eq!(p.strands.len(), 1);
    assert_eq!(p.steps, 10);
}

#[test]
fn syntax_and_structure_errors() {
    refused(&[], "[material\n", "t.toml:12: not valid TOML:");
    refused(
        &[("format = 1\n", "")],
        "",
        "t.toml:1: format: missing field `format`: this field is required",
    );
    refused(
        &[],
        "colour = 3\n",
        "t.toml:12: strands[0].colour: unknown field `colour`, expected one of",
    );
    refused(
        &[],
        "[material]\nradius = \"thick\"\n",
        "t.toml:13: material.radius: invalid type: string \"thick\", expected f32",
    );
    refused(
        &[("steps = 10", "steps = -5")],
        "",
        "t.toml:5: steps: invalid value: integer `-5`, expected u64",
    );
    refused(&[], "[head]\nmotion = \"spin\"\n", "t.toml:13: head.motion: unknown variant `spin`, expected one of `still`, `shake`, `keyframes`");
    refused(
        &[],
        "[hair.wig]\nx = 1\n",
        "t.toml:12: hair.wig: unknown variant `wig`, expected one of `stand`, `scalp`, `file`",
    );
    refused(
        &[],
        "[[grabs]]\nstrand = 0\nnode = 3\nforce_limit = 1.0\n",
        "t.toml:12: grabs[0].path: missing: give path (keys) or circle",
    );
}

#[test]
fn top_level_errors() {
    refused(
        &[("format = 1", "format = 2")],
        "",
        "t.toml:1: format: format 2 is not readable by this build, allowed format = 1 only",
    );
    refused(
        &[("name = \"t\"", "name = \"a b\"")],
        "",
        "t.toml:2: name: \"a b\" is not a scene name, allowed 1 to 64 characters",
    );
    refused(
        &[("name = \"t\"", "name = \"t\"\nabout = \"\"\"a\nb\"\"\"")],
        "",
        "t.toml:3: about: too long, allowed one line",
    );
    refused(
        &[("solver = \"rod\"", "solver = \"verlet\"")],
        "",
        "t.toml:3: solver: \"verlet\" is not known, allowed \"rod\" or \"dftl\"",
    );
    refused(
        &[("dt = 0.001", "dt = 0.5")],
        "",
        "t.toml:4: dt: 0.5 is out of range, allowed 0.00001 to 0.02 s",
    );
    refused(
        &[("steps = 10", "steps = 10\nduration = 1.0")],
        "",
        "t.toml:6: duration: both steps and duration are given, allowed one of them",
    );
    refused(
        &[("steps = 10\n", "")],
        "",
        "t.toml:1: steps: missing: give steps (a count) or duration (s)",
    );
    refused(
        &[("steps = 10", "steps = 0")],
        "",
        "t.toml:5: steps: 0 is out of range, allowed 1 to 100000000",
    );
    refused(
        &[("steps = 10", "duration = -1.0")],
        "",
        "t.toml:5: duration: -1 is out of range, allowed > 0 and <= 36000 s",
    );
    refused(
        &[("steps = 10", "duration = 0.0001")],
        "",
        "t.toml:5: duration: 0.0001 s is 0 steps of dt, allowed 1 to",
    );
    refused(
        &[("[\"gravity\"]", "[\"gravity\", \"magic\"]")],
        "",
        "t.toml:6: effects[1]: \"magic\" is not an effect, allowed \"gravity\", \"drag\"",
    );
    refused(
        &[("[\"gravity\"]", "[\"gravity\", \"gravity\"]")],
        "",
        "t.toml:6: effects[1]: \"gravity\" is listed twice, allowed each effect once",
    );
    refused(
        &[("[\"gravity\"]", "[\"shape\"]")],
        "",
        "t.toml:6: effects[0]: the rod solver cannot do \"shape\", allowed with it: \"gravity\"",
    );
    refused(
        &[("steps = 10", "steps = 10\nmode = \"fast\"")],
        "",
        "t.toml:6: mode: \"fast\" is not known, allowed \"converge\", \"fixed-cost\"",
    );
    refused(
        &[("steps = 10", "steps = 10\ngravity = [0.0, nan, 0.0]")],
        "",
        "t.toml:6: gravity: [0.0, NaN, 0.0] is out of range, allowed finite coordinates",
    );
    refused(
        &[("steps = 10", "steps = 10\ndrag = -1.0")],
        "",
        "t.toml:6: drag: -1 is out of range, allowed 0 to 0.01 kg/s",
    );
    refused(
        &[("[\"gravity\"]", "[\"drag\"]")],
        "",
        "t.toml:1: drag: missing: the effect \"drag\" is on, give drag",
    );
    refused(
        &[("steps = 10", "steps = 10\nstrands_per_block = 0")],
        "",
        "t.toml:6: strands_per_block: 0 is out of range, allowed 1 to 65536",
    );
    refused(
        &[("[\"gravity\"]", "[\"collisions\"]")],
        "",
        "t.toml:6: effects: \"collisions\" is on but there is no collider",
    );
    refused(
        &[("[\"gravity\"]", "[\"grabs\"]")],
        "",
        "t.toml:6: effects: \"grabs\" is on but there is no grab",
    );
    refused(
        &[("[\"gravity\"]", "[\"wind\"]")],
        "",
        "t.toml:1: wind: missing: the effect \"wind\" is on, give a [wind] table",
    );
}

#[test]
fn material_rod_and_dftl_errors() {
    refused(
        &[],
        "[material]\nyoungs_modulus = -1.0\n",
        "t.toml:13: material.youngs_modulus: -1 is out of range, allowed 1e7 Pa to 1e13 Pa",
    );
    refused(
        &[],
        "[material]\nshear_modulus = 1e14\n",
        "t.toml:13: material.shear_modulus: 100000000000000 is out of range, allowed 1e7 Pa to 1e13 Pa",
    );
    refused(
        &[],
        "[material]\nradius = 0.0\n",
        "t.toml:13: material.radius: 0 is out of range, allowed 1e-5 m to 5e-4 m",
    );
    refused(
        &[],
        "[material]\ndensity = 0.0\n",
        "t.toml:13: material.density: 0 is out of range, allowed 500 kg/m3 to 3000 kg/m3",
    );
    refused(
        &[],
        "[material]\nminor_axis_penalty = 0.5\n",
        "t.toml:13: material.minor_axis_penalty: 0.5 is out of range, allowed 1 to 10",
    );
    refused(
        &[],
        "[material]\ntip_stiffness = -0.5\n",
        "t.toml:13: material.tip_stiffness: -0.5 is out of range, allowed 0 to 1",
    );
    refused(
        &[],
        "[strands.material]\nradius = 1.0\n",
        "t.toml:13: strands[0].material.radius: 1 is out of range",
    );
    refused(
        &[],
        "[rod]\ntwist = \"exact\"\n",
        "t.toml:13: rod.twist: \"exact\" is not known, allowed \"hair-optimised\", \"newton\"",
    );
    refused(
        &[],
        "[rod]\nnewton_iterations = 0\n",
        "t.toml:13: rod.newton_iterations: 0 is out of range, allowed 1 to 100",
    );
    refused(
        &[],
        "[rod]\nnewton_tolerance = 0.0\n",
        "t.toml:13: rod.newton_tolerance: 0 is out of range, allowed > 0 and <= 1 rad",
    );
    refused(
        &[],
        "[rod]\nprojection_iterations = 0\n",
        "t.toml:13: rod.projection_iterations: 0 is out of range, allowed 1 to 1000",
    );
    refused(
        &[],
        "[rod]\nprojection_tolerance = 0.0\n",
        "t.toml:13: rod.projection_tolerance: 0 is out of range, allowed > 0",
    );
    refused(
        &[],
        "[dftl]\ndamping = 1.5\n",
        "t.toml:13: dftl.damping: 1.5 is out of range, allowed 0 to 1",
    );
    refused(
        &[],
        "[dftl]\nglobal_shape = -0.1\n",
        "t.toml:13: dftl.global_shape: -0.1 is out of range, allowed 0 to 1",
    );
    refused(
        &[],
        "[dftl]\nlocal_shape = 2.0\n",
        "t.toml:13: dftl.local_shape: 2 is out of range, allowed 0 to 1",
    );
    refused(
        &[],
        "[dftl]\nreference_dt = 0.0\n",
        "t.toml:13: dftl.reference_dt: 0 is out of range, allowed > 0 and <= 1 s",
    );
}

#[test]
fn head_motion_errors() {
    let shake = |body: &str| format!("[head.motion.shake]\n{body}");
    refused(
        &[],
        &shake("axis = [0.0, 0.0, 0.0]\namplitude = 0.5\nfrequency = 3.0\n"),
        "t.toml:13: head.motion.shake.axis: [0.0, 0.0, 0.0] is not a direction",
    );
    refused(
        &[],
        &shake(
            "axis = [0.0, 1.0, 0.0]\ncentre = [1e9, 0.0, 0.0]\namplitude = 0.5\nfrequency = 3.0\n",
        ),
        "t.toml:14: head.motion.shake.centre: [1000000000.0, 0.0, 0.0] is out of range",
    );
    refused(
        &[],
        &shake("axis = [0.0, 1.0, 0.0]\namplitude = 4.0\nfrequency = 3.0\n"),
        "t.toml:14: head.motion.shake.amplitude: 4 is out of range, allowed 0 to 3.1415927 rad",
    );
    refused(
        &[],
        &shake("axis = [0.0, 1.0, 0.0]\namplitude = 0.5\nfrequency = 3.0\npeak_speed = 10.0\n"),
        "t.toml:16: head.motion.shake.peak_speed: both frequency and peak_speed are given",
    );
    refused(&[], &shake("axis = [0.0, 1.0, 0.0]\namplitude = 0.5\n"), "t.toml:12: head.motion.shake.frequency: missing: give frequency (Hz) or peak_speed (rad/s)");
    refused(
        &[],
        &shake("axis = [0.0, 1.0, 0.0]\namplitude = 0.5\nfrequency = 500.0\n"),
        "t.toml:15: head.motion.shake.frequency: 500 is out of range, allowed 0 to 100 Hz",
    );
    refused(
        &[],
        &shake("axis = [0.0, 1.0, 0.0]\namplitude = 0.5\npeak_speed = 5000.0\n"),
        "t.toml:15: head.motion.shake.peak_speed: 5000 is out of range, allowed 0 to 1000 rad/s",
    );
    refused(
        &[],
        &shake("axis = [0.0, 1.0, 0.0]\namplitude = 0.0\npeak_speed = 10.0\n"),
        "t.toml:14: head.motion.shake.amplitude: is 0 with a peak_speed",
    );
    let keys = |body: &str| format!("[head.motion.keyframes]\nkeys = [\n{body}]\n");
    refused(
        &[],
        &keys(""),
        "t.toml:13: head.motion.keyframes.keys: allowed 1 to 100000 keys",
    );
    refused(
        &[],
        &keys("{ time = 0.5 },\n"),
        "t.toml:14: head.motion.keyframes.keys[0].time: 0.5 s, allowed: the first key at time 0",
    );
    refused(
        &[],
        &keys("{ time = -1.0 },\n"),
        "t.toml:14: head.motion.keyframes.keys[0].time: -1 is out of range, allowed 0 to 36000 s",
    );
    refused(&[], &keys("{ time = 0.0 },\n{ time = 0.0 },\n"), "t.toml:15: head.motion.keyframes.keys[1].time: 0 s is not after the previous key (0 s), allowed increasing times");
    refused(
        &[],
        &keys("{ time = 0.0, position = [0.0, 200.0, 0.0] },\n"),
        "t.toml:14: head.motion.keyframes.keys[0].position: [0.0, 200.0, 0.0] is out of range",
    );
    refused(
        &[],
        &keys("{ time = 0.0, axis = [0.0, 0.0, 0.0] },\n"),
        "t.toml:14: head.motion.keyframes.keys[0].axis: [0.0, 0.0, 0.0] is not a direction",
    );
    refused(
        &[],
        &keys("{ time = 0.0, angle = 9.0 },\n"),
        "t.toml:14: head.motion.keyframes.keys[0].angle: 9 is out of range",
    );
}

#[test]
fn collider_errors() {
    let c = |body: &str| format!("[[colliders]]\n{body}");
    refused(&[], &c("shape = \"cube\"\n"), "t.toml:13: colliders[0].shape: \"cube\" is not known, allowed \"sphere\", \"capsule\", \"plane\"");
    refused(&[], &c("shape = \"sphere\"\ncentre = [0.0, 0.0, 0.0]\nradius = 0.1\nnormal = [0.0, 1.0, 0.0]\n"), "t.toml:16: colliders[0].normal: not a field of a sphere, allowed \"centre\", \"radius\"");
    refused(
        &[],
        &c("shape = \"capsule\"\na = [0.0, 0.0, 0.0]\nradius = 0.1\n"),
        "t.toml:12: colliders[0].b: missing: a capsule needs \"a\", \"b\", \"radius\"",
    );
    refused(
        &[],
        &c("shape = \"plane\"\npoint = [0.0, 1e6, 0.0]\nnormal = [0.0, 1.0, 0.0]\n"),
        "t.toml:14: colliders[0].point: [0.0, 1000000.0, 0.0] is out of range",
    );
    refused(
        &[],
        &c("shape = \"sphere\"\ncentre = [0.0, 0.0, 0.0]\nradius = -0.1\n"),
        "t.toml:15: colliders[0].radius: -0.1 is out of range, allowed > 0 and <= 10 m",
    );
    refused(
        &[],
        &c("shape = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]\n"),
        "t.toml:15: colliders[0].normal: [0.0, 0.0, 0.0] is not a direction",
    );
    let nine =
        c("shape = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n").repeat(9);
    refused(
        &[],
        &nine,
        "t.toml:44: colliders[8]: 9 colliders, allowed at most 8",
    );
}

#[test]
fn hair_errors() {
    let stand = |body: &str| format!("[hair.stand]\n{body}");
    let ok = "wisps = 2\nnodes = 10\nlength = 0.1\n";
    refused(
        &[],
        &stand("wisps = 0\nnodes = 10\nlength = 0.1\n"),
        "t.toml:13: hair.stand.wisps: 0 is out of range, allowed 1 to 1000000",
    );
    refused(
        &[],
        &stand("wisps = 2\nnodes = 2\nlength = 0.1\n"),
        "t.toml:14: hair.stand.nodes: 2 is out of range, allowed 3 to 128",
    );
    refused(
        &[],
        &stand("wisps = 2\nnodes = 200\nlength = 0.1\n"),
        "t.toml:14: hair.stand.nodes: 200 is out of range, allowed 3 to 128",
    );
    refused(
        &[],
        &stand("wisps = 2\nnodes = 10\nlength = 0.0\n"),
        "t.toml:15: hair.stand.length: 0 is out of range, allowed > 0 and <= 10 m",
    );
    refused(
        &[],
        &stand(&format!("{ok}spacing = 0.0\n")),
        "t.toml:16: hair.stand.spacing: 0 is out of range",
    );
    refused(
        &[],
        &stand(&format!("{ok}origin = [inf, 0.0, 0.0]\n")),
        "t.toml:16: hair.stand.origin: [inf, 0.0, 0.0] is out of range",
    );
    refused(
        &[],
        &stand(&format!("{ok}direction = [0.0, 0.0, 0.0]\n")),
        "t.toml:16: hair.stand.direction: [0.0, 0.0, 0.0] is not a direction",
    );
    refused(
        &[],
        &stand(&format!("{ok}followers = 20000\n")),
        "t.toml:16: hair.stand.followers: 20000 is out of range, allowed 0 to 10000",
    );
    refused(&[], &stand(&format!("{ok}style = {{ shape = \"frizzy\" }}\n")), "t.toml:16: hair.stand.style.shape: \"frizzy\" is not known, allowed \"straight\", \"wavy\", \"curly\"");
    refused(&[], &stand(&format!("{ok}style = {{ shape = \"wavy\", amplitude = 0.01 }}\n")), "t.toml:16: hair.stand.style.period: missing: shape \"wavy\" needs \"amplitude\", \"period\"");
    refused(
        &[],
        &stand(&format!(
            "{ok}style = {{ shape = \"straight\", radius = 0.01 }}\n"
        )),
        "t.toml:16: hair.stand.style.radius: not used by shape \"straight\", allowed with it: none",
    );
    refused(
        &[],
        &stand(&format!(
            "{ok}style = {{ shape = \"curly\", radius = 2.0, period = 0.01 }}\n"
        )),
        "t.toml:16: hair.stand.style.radius: 2 is out of range, allowed > 0 and <= 1 m",
    );
    let scalp = |body: &str| format!("[hair.scalp]\nleaders = 5\nnodes = 10\nlength = 0.1\n{body}");
    refused(
        &[],
        "[hair.scalp]\nleaders = 0\nnodes = 10\nlength = 0.1\n",
        "t.toml:13: hair.scalp.leaders: 0 is out of range",
    );
    refused(
        &[],
        &scalp("centre = [nan, 0.0, 0.0]\n"),
        "t.toml:16: hair.scalp.centre: [NaN, 0.0, 0.0] is out of range",
    );
    refused(
        &[],
        &scalp("radius = 0.0\n"),
        "t.toml:16: hair.scalp.radius: 0 is out of range",
    );
    refused(
        &[],
        &scalp("cap_angle = 4.0\n"),
        "t.toml:16: hair.scalp.cap_angle: 4 is out of range, allowed > 0 and <= 3.1415927 rad",
    );
    refused(
        &[],
        &scalp("followers = 20000000\n"),
        "t.toml:16: hair.scalp.followers: 20000000 is out of range",
    );
    refused(
        &[],
        &scalp("style = { shape = \"curly\", radius = 0.01 }\n"),
        "t.toml:16: hair.scalp.style.period: missing",
    );
    let file = |body: &str| format!("[hair.file]\n{body}");
    refused(
        &[],
        &file("path = \"\"\n"),
        "t.toml:13: hair.file.path: empty, allowed the path of a hair file",
    );
    refused(
        &[],
        &file("path = \"a.txt\"\n"),
        "t.toml:13: hair.file.path: \"a.txt\" is not a hair file, allowed a .hair, .tfx, .obj, .ply or .usda file",
    );
    refused(
        &[],
        &file("path = \"a.hair\"\nscale = 0.0\n"),
        "t.toml:14: hair.file.scale: 0 is out of range",
    );
    refused(
        &[],
        &file("path = \"a.hair\"\nup = \"x\"\n"),
        "t.toml:14: hair.file.up: \"x\" is not known, allowed \"y\", \"z\"",
    );
    refused(
        &[],
        &file("path = \"no-such-file.hair\"\n"),
        "t.toml:13: hair.file.path: cannot read \"no-such-file.hair\":",
    );
    refused(
        &[],
        &file("path = \"a.hair\"\nnodes = 2\n"),
        "t.toml:14: hair.file.nodes: 2 is out of range, allowed 3 to 128",
    );
    refused(
        &[],
        &file("path = \"a.hair\"\nmax_strands = 0\n"),
        "t.toml:14: hair.file.max_strands: 0 is out of range, allowed 1 to 1000000",
    );
    refused(
        &[],
        &file("path = \"a.hair\"\nmin_length = -1.0\n"),
        "t.toml:14: hair.file.min_length: -1 is out of range, allowed 0 to 10 m",
    );
}

#[test]
fn strand_errors() {
    let only = |body: &str| -> Vec<(&'static str, String)> {
        vec![("[[strands]]\nroot = [0.0, 0.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nlength = 0.1\nnodes = 5\n", format!("[[strands]]\n{body}"))]
    };
    let run = |body: &str, expected: &str| {
        let pairs = only(body);
        let replace: Vec<(&str, &str)> = pairs.iter().map(|(a, b)| (*a, b.as_str())).collect();
        refused(&replace, "", expected);
    };
    run("", "t.toml:7: strands[0].root: missing: a generated strand needs root, direction, length and nodes (or give points)");
    run(
        "points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]]\nnodes = 3\n",
        "t.toml:9: strands[0].nodes: given with points, allowed either points",
    );
    run(
        "points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]\n",
        "t.toml:8: strands[0].points: 2 is out of range, allowed 3 to 128",
    );
    run(
        "points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, nan, 0.0]]\n",
        "t.toml:8: strands[0].points[2]: [0.2, NaN, 0.0] is out of range",
    );
    run("points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.0, 0.0]]\n", "t.toml:7: strands[0]: segment 1 is shorter than 0.000001 m, allowed: segments of at least 1e-6 m that never fold back");
    run(
        "points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]]\n",
        "t.toml:7: strands[0]: the polyline folds back on itself at node 1",
    );
    run(
        "root = [0.0, 0.0, 0.0]\ndirection = [0.0, 0.0, 0.0]\nlength = 0.1\nnodes = 5\n",
        "t.toml:9: strands[0].direction: [0.0, 0.0, 0.0] is not a direction",
    );
    run("root = [0.0, 0.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nlength = 0.1\nnodes = 5\nshape = \"wavy\"\namplitude = 0.01\n", "t.toml:7: strands[0].period: missing: shape \"wavy\" needs");
    let none = BASE.replace("[[strands]]\nroot = [0.0, 0.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nlength = 0.1\nnodes = 5\n", "");
    assert!(error(&none).starts_with("t.toml:1: hair: the scene has no strands, allowed: [hair.stand], [hair.scalp], [hair.file] or [[strands]]"));
}

#[test]
fn grab_wind_sph_and_output_errors() {
    let grab = |body: &str| format!("[[grabs]]\n{body}");
    let path = "path = [{ time = 0.0, target = [0.1, 0.0, 0.0] }]\n";
    refused(
        &[],
        &grab(&format!("strand = 0\nnode = 3\nforce_limit = 0.0\n{path}")),
        "t.toml:15: grabs[0].force_limit: 0 is out of range, allowed > 0 and <= 1000 N",
    );
    refused(
        &[],
        &grab("strand = 0\nnode = 3\nforce_limit = 1.0\npath = []\n"),
        "t.toml:16: grabs[0].path: allowed 1 to 100000 keys",
    );
    refused(&[], &grab("strand = 0\nnode = 3\nforce_limit = 1.0\npath = [{ time = 1.0, target = [0.0, 0.0, 0.0] }, { time = 0.5, target = [0.0, 0.0, 0.0] }]\n"), "t.toml:16: grabs[0].path[1].time: 0.5 s is not after the previous key (1 s)");
    refused(&[], &grab("strand = 0\nnode = 3\nforce_limit = 1.0\npath = [{ time = 0.0, target = [0.0, -1e3, 0.0] }]\n"), "t.toml:16: grabs[0].path[0].target: [0.0, -1000.0, 0.0] is out of range");
    refused(
        &[],
        &grab(&format!(
            "strand = 0\nnode = 3\nforce_limit = 1.0\n{path}release = -1.0\n"
        )),
        "t.toml:17: grabs[0].release: -1 is out of range",
    );
    refused(
        &[],
        &grab(&format!("strand = 4\nnode = 3\nforce_limit = 1.0\n{path}")),
        "t.toml:13: grabs[0].strand: strand 4 does not exist, allowed 0 to 0",
    );
    refused(
        &[],
        &grab(&format!("strand = 0\nnode = 1\nforce_limit = 1.0\n{path}")),
        "t.toml:14: grabs[0].node: node 1 is not a free node of strand 0, allowed 2 to 4",
    );
    let five = grab(&format!("strand = 0\nnode = 3\nforce_limit = 1.0\n{path}")).repeat(5);
    refused(
        &[],
        &five,
        "t.toml:32: grabs[4]: 5 grabs, allowed at most 4",
    );
    let wind = "[wind]\ndirection = [1.0, 0.0, 0.0]\nstrength = 2.0\n";
    let circle = |body: &str| {
        format!("[[grabs]]\nstrand = 0\nnode = 3\nforce_limit = 1.0\ncircle = {{ {body} }}\n")
    };
    refused(
        &[],
        &format!(
            "{}path = []\n",
            circle("start = [0.1, 0.0, 0.0], radius = 0.01, frequency = 2.0")
        ),
        "t.toml:16: grabs[0].circle: both path and circle are given, allowed one of them",
    );
    refused(
        &[],
        &circle("start = [0.1, 0.0, 1e3], radius = 0.01, frequency = 2.0"),
        "t.toml:16: grabs[0].circle.start: [0.1, 0.0, 1000.0] is out of range",
    );
    refused(
        &[],
        &circle("start = [0.1, 0.0, 0.0], radius = 0.0, frequency = 2.0"),
        "t.toml:16: grabs[0].circle.radius: 0 is out of range, allowed > 0 and <= 10 m",
    );
    refused(
        &[],
        &circle("start = [0.1, 0.0, 0.0], radius = 0.01, frequency = -2.0"),
        "t.toml:16: grabs[0].circle.frequency: -2 is out of range, allowed 0 to 100 Hz",
    );
    refused(
        &[],
        &circle("start = [0.1, 0.0, 0.0], radius = 0.01, frequency = 2.0, u = [0.0, 0.0, 0.0]"),
        "t.toml:16: grabs[0].circle.u: [0.0, 0.0, 0.0] is not a direction",
    );
    refused(
        &[],
        &circle("start = [0.1, 0.0, 0.0], radius = 0.01, frequency = 2.0, v = [0.0, nan, 0.0]"),
        "t.toml:16: grabs[0].circle.v: [0.0, NaN, 0.0] is not a direction",
    );
    refused(
        &[],
        "[wind]\ndirection = [0.0, 0.0, 0.0]\nstrength = 2.0\n",
        "t.toml:13: wind.direction: [0.0, 0.0, 0.0] is not a direction",
    );
    refused(
        &[],
        "[wind]\ndirection = [1.0, 0.0, 0.0]\nstrength = -2.0\n",
        "t.toml:14: wind.strength: -2 is out of range, allowed 0 to 1000 m/s2",
    );
    refused(
        &[],
        &format!("{wind}gust = 20.0\n"),
        "t.toml:15: wind.gust: 20 is out of range, allowed 0 to 10",
    );
    refused(
        &[],
        &format!("{wind}gust_frequency = -2.0\n"),
        "t.toml:15: wind.gust_frequency: -2 is out of range, allowed 0 to 1000 Hz",
    );
    refused(
        &[],
        &format!("{wind}seed = -1\n"),
        "t.toml:15: wind.seed: invalid value: integer `-1`, expected u32",
    );
    let sph = |field: &str, value: &str| {
        let mut body = "[hair-hair]\nsmoothing_length = 0.01\nrest_density = 100.0\nstiffness = 0.1\nviscosity = 0.1\n".to_string();
        body = if let Some(start) = body.find(&format!("{field} = ")) {
            let end = start + body[start..].find('\n').unwrap_or(0);
            format!("{}{field} = {value}{}", &body[..start], &body[end..])
        } else {
            format!("{body}{field} = {value}\n")
        };
        body
    };
    refused(
        &[],
        &sph("smoothing_length", "0.0"),
        "t.toml:13: hair-hair.smoothing_length: 0 is out of range, allowed 0.0001 to 1 m",
    );
    refused(
        &[],
        &sph("rest_density", "-1.0"),
        "t.toml:14: hair-hair.rest_density: -1 is out of range",
    );
    refused(
        &[],
        &sph("stiffness", "0.6"),
        "t.toml:15: hair-hair.stiffness: 0.6 is out of range, allowed 0 to 0.5 m2/s2",
    );
    refused(
        &[],
        &sph("viscosity", "1e9"),
        "t.toml:16: hair-hair.viscosity: 1000000000 is out of range, allowed 0 to 200",
    );
    refused(
        &[],
        &sph("max_neighbours", "0"),
        "t.toml:17: hair-hair.max_neighbours: 0 is out of range, allowed 1 to 256",
    );
    refused(
        &[],
        &sph("skip_same_strand", "99"),
        "t.toml:17: hair-hair.skip_same_strand: 99 is out of range, allowed 0 to 64",
    );
    refused(
        &[],
        "[output]\nevery = 0\n",
        "t.toml:13: output.every: 0 is out of range",
    );
    refused(&[], "[output]\nformats = [\"obj\", \"fbx\"]\n", "t.toml:13: output.formats[1]: \"fbx\" is not known, allowed \"obj\", \"ply\", \"hair\", \"usda\", \"tfx\"");
    refused(
        &[],
        "[output]\npicture = \"jpeg\"\n",
        "t.toml:13: output.picture: \"jpeg\" is not known, allowed \"png\", \"gif\"",
    );
    refused(
        &[],
        "[output]\nwidth = 1\n",
        "t.toml:13: output.width: 1 is out of range, allowed 16 to 8192",
    );
    refused(
        &[],
        "[output]\nheight = 10000\n",
        "t.toml:13: output.height: 10000 is out of range, allowed 16 to 8192",
    );
}

#[test]
fn the_dftl_solver_refuses_what_it_cannot_do() {
    let dftl = [("solver = \"rod\"", "solver = \"dftl\"")];
    refused(
        &[dftl[0], ("[\"gravity\"]", "[\"gravity\", \"bending\"]")],
        "",
        "t.toml:6: effects[1]: the dftl solver cannot do \"bending\"",
    );
    // DFTL grabs any free node, mid-strand too, and refuses the root's, as the rod does.
    let grab = |node: u32| {
        format!(
            "[[grabs]]\nstrand = 0\nnode = {node}\nforce_limit = 1.0\n\
             path = [{{ time = 0.0, target = [0.1, 0.0, 0.0] }}]\n"
        )
    };
    let effects = ("[\"gravity\"]", "[\"gravity\", \"grabs\"]");
    let text = scene(&[dftl[0], effects], &grab(3));
    assert!(Scene::parse_and_prepare(&text, "t.toml", Path::new(".")).is_ok());
    refused(
        &[dftl[0], effects],
        &grab(1),
        "t.toml:14: grabs[0].node: node 1 is not a free node of strand 0, allowed 2 to 4",
    );
}

#[test]
fn builtin_errors_name_the_builtin() {
    let mut scene = crate::builtin::firmware_scene();
    scene.dt = 1.0;
    let e = scene.prepare().unwrap_err().in_builtin("firmware");
    assert_eq!(
        e.to_string(),
        "builtin:firmware: dt: 1 is out of range, allowed 0.00001 to 0.02 s"
    );
}

/// The documented example with each line dropped, cut short at many places, or with a number
/// replaced by an extreme: a scene or one placed error every time, never a panic.
#[test]
fn mangled_scenes_give_errors_not_panics() {
    let doc = include_str!("../../../../docs/scene-format.md");
    let start = doc.find("```toml\n").unwrap() + "```toml\n".len();
    let example = &doc[start..start + doc[start..].find("```").unwrap()];
    let lines: Vec<&str> = example.lines().collect();
    let mut variants: Vec<String> = Vec::new();
    for i in 0..lines.len() {
        let mut kept = lines.clone();
        kept.remove(i);
        variants.push(kept.join("\n"));
        for extreme in ["-1e39", "0", "1e-45", "nan", "-7", "\"x\"", "[]"] {
            if let Some(eq) = lines[i].find(" = ") {
                let mut changed = lines.clone();
                let replaced = format!("{} = {extreme}", &lines[i][..eq]);
                changed[i] = &replaced;
                variants.push(changed.join("\n"));
            }
        }
    }
    for cut in (0..example.len()).step_by(41) {
        if example.is_char_boundary(cut) {
            variants.push(example[..cut].to_string());
        }
    }
    let mut refused = 0;
    for text in &variants {
        match Scene::parse_and_prepare(text, "t.toml", Path::new(".")) {
            Ok((scene, _)) => {
                assert_eq!(Scene::from_toml(&scene.to_toml(), "again").unwrap(), scene);
            }
            Err(e) => {
                refused += 1;
                let line = e.to_string();
                assert!(line.starts_with("t.toml:"), "{line}");
                assert!(!line.contains('\n'), "{line}");
            }
        }
    }
    assert!(
        refused > variants.len() / 2,
        "{refused} of {}",
        variants.len()
    );
}
