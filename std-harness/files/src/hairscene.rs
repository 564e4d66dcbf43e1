//! The default scene around a hair file (`hairsim run head.hair`): DFTL with shape
//! preservation at 1 ms, gravity, drag and inextensibility, the head still, and a head sphere
//! fitted to the strands' roots (with collisions on) when the roots outline one, touching the
//! scalp at its lowest held node.
//!
//! Why DFTL and not the rod: real hair files hold tight curls and short, uneven segments, which
//! put an explicit rod far past its stability limit at 1 ms; DFTL is stable for any shape at a
//! fixed cost, and its shape constraints keep the style the file was made with. A TOML scene
//! with a `[hair.file]` table runs a file with the rod.
//!
//! Units: without `--scale` the file is scaled so that the head fitted to its roots has
//! [`HEAD_RADIUS`] (or, with no head to fit, so that its median strand is [`HAIR_LENGTH`]
//! long): exporters use centimetres, decimetres or arbitrary units, and a scene in the wrong
//! units runs hair a hundred times too short or too long. The summary names the scale chosen.
//! Without `--up` a `.hair` file is taken as Z-up (Cem Yuksel's models are) and a `.tfx` as
//! Y-up (TressFX's convention).
//!
//! The file is read (by the `hairfile` module) once here to fit the head to its roots, and
//! again when the scene is prepared, like any `[hair.file]`.

use std::path::Path;

use hairsim_core::Vec3;

use crate::scene::{ColliderSpec, FieldError, FileSpec, HairFiles, HairSpec, Scene, FORMAT};

/// Options for a hair file given as the scene (`hairsim run head.hair`).
#[derive(Clone, Debug, Default)]
pub struct HairFileOptions {
    /// Factor from the file's units to metres.
    pub scale: Option<f32>,
    /// The file's up axis, `y` or `z`.
    pub up: Option<String>,
}

/// Strands the default scene keeps at most, picked evenly through the file.
pub const DEFAULT_MAX_STRANDS: u32 = 1000;
/// Nodes every strand is resampled to in the default scene.
pub const DEFAULT_NODES: u32 = 24;
/// Radius of the head fitted to a file's roots once scaled, m (an adult head).
pub const HEAD_RADIUS: f32 = 0.09;
/// Median strand length of a file with no head to fit once scaled, m.
pub const HAIR_LENGTH: f32 = 0.25;

/// The default scene for the hair file at `path`.
pub fn scene_for_hair_file(path: &Path, options: &HairFileOptions) -> Result<Scene, FieldError> {
    scene_for_hair_file_in(path, options, HairFiles::Disk(Path::new(".")))
}

/// The default scene for the hair file at `path`, read from `files`.
pub fn scene_for_hair_file_in(
    path: &Path,
    options: &HairFileOptions,
    files: HairFiles<'_>,
) -> Result<Scene, FieldError> {
    // Checked like a scene's [hair.file] table, so --scale and --up get the same messages.
    let bare = scene_around(path, options, &[]);
    crate::scene::validate_only(&bare)?;
    let Some(HairSpec::File(file)) = &bare.hair else {
        return Ok(bare);
    };
    let model = crate::scene::prepare::read_hair_file(file, files)?;
    let mut roots: Vec<Vec3> = model
        .strands
        .iter()
        .filter_map(|s| s.first().copied())
        .collect();
    let mut options = options.clone();
    if options.scale.is_none() {
        let scale = automatic_scale(&roots, &model.strands);
        roots.iter_mut().for_each(|r| *r *= scale);
        options.scale = Some(scale);
    }
    let mut scene = scene_around(path, &options, &roots);
    // The strands as the run will build them (in metres, and picked from those the scale
    // keeps longer than `min_length`).
    if let Some(HairSpec::File(file)) = &scene.hair {
        let strands = crate::scene::prepare::read_hair_file(file, files)?.strands;
        touch_the_scalp(&mut scene, &strands);
    }
    Ok(scene)
}

/// The share of its distance from the centre by which the fitted head stays below the lowest
/// held node: 0.1 %, 0.09 mm on a 9 cm head.
const SCALP_CLEARANCE: f32 = 1e-3;

/// Brings the fitted head sphere of `scene` down from just inside the roots to the lowest held
/// node (0.1 % below it): nodes 0 and 1 of every strand of `strands`, which
/// the head carries and no collision moves. A head sphere above a held node would grow the
/// strand out of the head, its node 2 pushed out beside its node 1 at every step, a kink at
/// the root. So the sphere touches the scalp where it is lowest; the rest of the groom may dip
/// into it (a real scalp is no sphere), and those nodes start outside it, each at its length
/// from the one before (`Prepared::start_strands`), and rest pressed onto it.
fn touch_the_scalp(scene: &mut Scene, strands: &[Vec<Vec3>]) {
    for collider in &mut scene.colliders {
        let (Some(centre), Some(radius)) = (collider.centre, collider.radius.as_mut()) else {
            continue;
        };
        let centre = Vec3::from_array(centre);
        let lowest = strands
            .iter()
            .flat_map(|s| s.iter().take(2))
            .map(|p| (*p - centre).length())
            .filter(|d| d.is_finite())
            .fold(f32::INFINITY, f32::min);
        *radius = radius.min(lowest * (1.0 - SCALP_CLEARANCE));
    }
}

/// The factor that gives a file read in its own units a human size: the head fitted to its
/// `roots` becomes [`HEAD_RADIUS`] across, or, with no head to fit, the median of `strands`'
/// lengths becomes [`HAIR_LENGTH`]; 1 when neither can be measured.
#[must_use]
pub fn automatic_scale(roots: &[Vec3], strands: &[Vec<Vec3>]) -> f32 {
    if let Some((_, radius)) = fit_sphere_within(roots, f32::MAX) {
        if radius > 0.0 {
            return HEAD_RADIUS / radius;
        }
    }
    let mut lengths: Vec<f32> = strands
        .iter()
        .map(|s| s.windows(2).map(|w| (w[1] - w[0]).length()).sum())
        .filter(|l: &f32| l.is_finite() && *l > 0.0)
        .collect();
    lengths.sort_by(f32::total_cmp);
    match lengths.get(lengths.len() / 2) {
        Some(median) => HAIR_LENGTH / median,
        None => 1.0,
    }
}

/// The default scene for the hair file at `path` whose strand roots (after `--scale` and
/// `--up`) are `roots`.
#[must_use]
pub fn scene_around(path: &Path, options: &HairFileOptions, roots: &[Vec3]) -> Scene {
    let name: String = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
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
    let mut effects: Vec<String> = ["gravity", "drag", "inextensibility", "shape"]
        .iter()
        .map(|e| (*e).to_string())
        .collect();
    let up = options.up.clone().or_else(|| {
        let hair = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("hair"));
        Some(if hair { "z" } else { "y" }.to_string())
    });
    let colliders: Vec<ColliderSpec> = fit_sphere(roots)
        .map(|(centre, radius)| ColliderSpec {
            shape: "sphere".into(),
            attached: Some(true),
            centre: Some(centre.to_array()),
            // Just inside the roots, so the held root nodes never start in contact.
            radius: Some(radius * 0.97),
            a: None,
            b: None,
            point: None,
            normal: None,
        })
        .into_iter()
        .collect();
    if !colliders.is_empty() {
        effects.push("collisions".into());
    }
    Scene {
        format: FORMAT,
        name: if name.is_empty() { "hair".into() } else { name },
        about: Some(format!("default scene around {}", path.display())),
        solver: "dftl".into(),
        dt: 0.001,
        steps: Some(1000),
        duration: None,
        effects,
        mode: None,
        gravity: None,
        drag: Some(2.0e-7),
        strands_per_block: None,
        material: None,
        rod: None,
        dftl: None,
        head: None,
        colliders,
        hair: Some(HairSpec::File(FileSpec {
            path: path.display().to_string(),
            scale: options.scale,
            up,
            nodes: Some(DEFAULT_NODES),
            max_strands: Some(DEFAULT_MAX_STRANDS),
            min_length: None,
        })),
        strands: Vec::new(),
        grabs: Vec::new(),
        wind: None,
        hair_hair: None,
        output: None,
    }
}

/// The sphere through `points` in the least-squares sense (algebraic fit:
/// `|p|² = 2 c·p + (r² − |c|²)`, solved by Gaussian elimination in `f64`), or `None` when the
/// points do not outline a head (fewer than 4, nearly coplanar, spread along a strip rather
/// than over a scalp, or a radius past 10 m).
#[must_use]
pub fn fit_sphere(points: &[Vec3]) -> Option<(Vec3, f32)> {
    fit_sphere_within(points, 10.0)
}

/// [`fit_sphere`] with a radius of at most `max_radius`.
fn fit_sphere_within(points: &[Vec3], max_radius: f32) -> Option<(Vec3, f32)> {
    if points.len() < 4 {
        return None;
    }
    // Normal equations A^T A x = A^T b with rows (2x, 2y, 2z, 1) and b = |p|².
    let mut m = [[0.0f64; 5]; 4];
    for p in points {
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        let row = [2.0 * x, 2.0 * y, 2.0 * z, 1.0];
        let b = x * x + y * y + z * z;
        for i in 0..4 {
            for j in 0..4 {
                m[i][j] += row[i] * row[j];
            }
            m[i][4] += row[i] * b;
        }
    }
    let scale = m
        .iter()
        .map(|r| r[0].abs().max(r[3].abs()))
        .fold(0.0, f64::max);
    for col in 0..4 {
        let pivot = (col..4).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[pivot][col].abs() <= 1e-12 * scale.max(1e-300) {
            return None;
        }
        m.swap(col, pivot);
        let pivot_row = m[col];
        for (row, r) in m.iter_mut().enumerate() {
            if row != col {
                let f = r[col] / pivot_row[col];
                for (a, b) in r.iter_mut().zip(pivot_row).skip(col) {
                    *a -= f * b;
                }
            }
        }
    }
    let c = [m[0][4] / m[0][0], m[1][4] / m[1][1], m[2][4] / m[2][2]];
    let k = m[3][4] / m[3][3];
    let r2 = k + c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let r = libm::sqrt(r2);
    let fits = r2 > 0.0 && r <= f64::from(max_radius) && c.iter().all(|v| v.is_finite());
    (fits && covers_a_scalp(points, r as f32))
        .then(|| (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32), r as f32))
}

/// Whether `points` spread over a scalp of a sphere of `radius` rather than along a line on
/// it: the bounding box's second-largest side is at least half the radius. A mohawk's roots
/// lie on a narrow strip, which fits a sphere of any size and is no head.
fn covers_a_scalp(points: &[Vec3], radius: f32) -> bool {
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let mut sides = (hi - lo).to_array();
    sides.sort_by(f32::total_cmp);
    sides[1] >= 0.5 * radius
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::generate::scalp_roots;

    #[test]
    fn fits_the_sphere_of_a_scalp() {
        let centre = Vec3::new(0.01, 1.6, -0.02);
        let roots: Vec<Vec3> = scalp_roots(200, centre, 0.09, 1.0)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let (c, r) = fit_sphere(&roots).unwrap();
        assert!((c - centre).length() < 1e-4, "{c}");
        assert!((r - 0.09).abs() < 1e-4, "{r}");
    }

    #[test]
    fn refuses_points_that_outline_no_sphere() {
        assert_eq!(fit_sphere(&[Vec3::ZERO, Vec3::X, Vec3::Y]), None);
        let plane: Vec<Vec3> = (0..20)
            .map(|i| Vec3::new((i % 5) as f32, 0.0, (i / 5) as f32))
            .collect();
        assert_eq!(fit_sphere(&plane), None);
        // A mohawk: roots along a narrow strip over the top of a head.
        let strip: Vec<Vec3> = (0..40)
            .map(|i| {
                let a = -1.0 + 0.05 * i as f32;
                let x = 0.004 * (i % 3) as f32;
                Vec3::new(x, 0.1 * a.cos(), 0.1 * a.sin())
            })
            .collect();
        assert_eq!(fit_sphere(&strip), None);
    }

    #[test]
    fn the_automatic_scale_makes_a_head_of_human_size() {
        // A scalp in centimetres: the head fitted to it becomes HEAD_RADIUS across.
        let roots: Vec<Vec3> = scalp_roots(200, Vec3::ZERO, 9.0, 1.0)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let scale = automatic_scale(&roots, &[]);
        assert!((scale - HEAD_RADIUS / 9.0).abs() < 1e-6, "{scale}");
        // No head to fit: the median strand becomes HAIR_LENGTH long.
        let strands: Vec<Vec<Vec3>> = [2.0f32, 5.0, 50.0]
            .iter()
            .map(|&l| vec![Vec3::ZERO, Vec3::new(0.0, -l, 0.0)])
            .collect();
        assert!((automatic_scale(&[Vec3::ZERO; 3], &strands) - HAIR_LENGTH / 5.0).abs() < 1e-6);
        assert_eq!(automatic_scale(&[], &[]), 1.0);
    }

    #[test]
    fn the_default_scene_turns_collisions_on_only_with_a_fitted_head() {
        let path = Path::new("wig.hair");
        let bare = scene_around(path, &HairFileOptions::default(), &[]);
        assert!(bare.colliders.is_empty() && !bare.effects.contains(&"collisions".into()));
        let roots: Vec<Vec3> = scalp_roots(50, Vec3::ZERO, 0.1, 1.2)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let fitted = scene_around(path, &HairFileOptions::default(), &roots);
        assert_eq!(fitted.colliders.len(), 1);
        assert!(fitted.effects.contains(&"collisions".into()));
        assert_eq!(fitted.name, "wig");
    }
}
