//! Pictures of frames: anti-aliased strands coloured root → tip over the colliders (sphere →
//! disc, capsule → stadium, plane → edge line with its solid side shaded), seen through an
//! orthographic camera; PNG stills and animated GIFs written a frame at a time.
//!
//! The look of `hairsim view`'s page (`std-harness/viewer/web/look.js` and `render-gl.js`) as
//! far as a CPU rasteriser allows: the same colours and light, each piece of a strand shaded
//! by the page's Kajiya–Kay terms (diffuse from the angle between the strand and the light,
//! a narrow white highlight and a broad tinted one) and its depth cue (hair on the far side
//! of the light is darker), in a few steps of brightness; spheres and capsules lit by
//! gradients toward the light.
//!
//! Drawn with `tiny-skia`. Strand segments and colliders are painted far to near (a painter's
//! algorithm over segment midpoints and collider centres), so hair behind the head is hidden by
//! it and hair in front covers it.

mod camera;
mod gif_writer;

use hairsim_core::{Shape, Vec3};
use tiny_skia::{
    Color, FillRule, GradientStop, LineCap, LineJoin, LinearGradient, Paint, PathBuilder, Pixmap,
    Point, RadialGradient, Shader, SpreadMode, Stroke, Transform,
};

pub use camera::{Camera, View, MARGIN};
pub use gif_writer::GifWriter;

/// Why a picture could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// Width or height is zero or too large.
    #[error("bad picture size {width}×{height} (1 ..= {max} pixels each way)")]
    BadSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Largest allowed side.
        max: u32,
    },
    /// PNG encoding failed.
    #[error("PNG encoding: {0}")]
    Png(String),
    /// GIF encoding or writing failed.
    #[error("GIF encoding: {0}")]
    Gif(#[from] gif::EncodingError),
}

impl From<PictureError> for crate::export::ExportError {
    fn from(e: PictureError) -> Self {
        crate::export::ExportError::Picture(Box::new(e))
    }
}

/// Largest picture side: GIF stores sizes in 16 bits, and this keeps a frame's buffer sane.
pub const MAX_SIDE: u32 = 8192;

/// Colours and widths. Colours are sRGB `[r, g, b]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Style {
    /// Background.
    pub background: [u8; 3],
    /// Strand colour at the root.
    pub root: [u8; 3],
    /// Strand colour at the tip.
    pub tip: [u8; 3],
    /// Strand stroke width, pixels (≤ 1: anti-aliased hairlines, much faster to draw).
    pub strand_width: f32,
    /// Collider fill.
    pub collider_fill: [u8; 3],
    /// Collider outline (and a plane's edge line).
    pub collider_edge: [u8; 3],
    /// Shading of a plane's solid side.
    pub plane_fill: [u8; 3],
}

impl Default for Style {
    /// The page's colours (`look.js`).
    fn default() -> Self {
        Style {
            background: [21, 23, 28],
            root: [58, 32, 18],
            tip: [222, 168, 84],
            strand_width: 1.0,
            collider_fill: [150, 160, 176],
            collider_edge: [40, 44, 54],
            plane_fill: [34, 38, 46],
        }
    }
}

/// Toward the light, from the hair (world, Y up): the page's light (`look.js`).
const LIGHT: Vec3 = Vec3::new(0.45, 0.8, 0.4);

/// Steps of the shading's brightness: each is a colour of its own, and so a stroke.
const LIGHT_STEPS: f32 = 6.0;

/// The page's hair shading (`render-gl.js`) for a piece along unit `tangent` at `point`:
/// the factor on its colour and the white added (0 ..= 1), each in [`LIGHT_STEPS`] steps.
/// `view` points from the hair to the camera; `volume` is the hair's centre and radius.
fn shading(tangent: Vec3, point: Vec3, view: Vec3, volume: (Vec3, f32)) -> (f32, f32) {
    let light = LIGHT.normalize();
    let half = (light + view).normalize();
    let (tl, th) = (tangent.dot(light), tangent.dot(half));
    let diffuse = (1.0 - tl * tl).max(0.0).sqrt();
    let sin_th = (1.0 - th * th).max(0.0).sqrt();
    let depth = (0.5 - 0.5 * (point - volume.0).dot(light) / volume.1).clamp(0.0, 1.0);
    let shadow = 1.0 + (0.35 - 1.0) * depth;
    let factor = 0.25 + 0.75 * diffuse * shadow + 0.45 * sin_th.powi(18) * shadow;
    let white = 0.3 * sin_th.powi(90) * shadow;
    let step = |x: f32| (x * LIGHT_STEPS).round() / LIGHT_STEPS;
    (step(factor), step(white))
}

/// The hair's centre and radius (the depth cue's volume).
fn volume<S: AsRef<[Vec3]>>(strands: &[S]) -> (Vec3, f32) {
    let finite = || {
        strands
            .iter()
            .flat_map(AsRef::as_ref)
            .filter(|p| p.is_finite())
    };
    let count = finite().count().max(1) as f32;
    let centre = finite().fold(Vec3::ZERO, |sum, p| sum + *p) / count;
    let radius = finite()
        .map(|p| (*p - centre).length())
        .fold(1e-3, f32::max);
    (centre, radius)
}

impl Style {
    /// The default style with a strand width suited to `strands` strands: 2 px for a few
    /// strands (≤ 64), 1.5 px up to 1000, 1 px beyond (where tiny-skia's fast anti-aliased
    /// hairlines also keep a 150 000-segment frame near 0.2–0.5 s at 400×400).
    #[must_use]
    pub fn for_strand_count(strands: usize) -> Style {
        let strand_width = match strands {
            0..=64 => 2.0,
            65..=1000 => 1.5,
            _ => 1.0,
        };
        Style {
            strand_width,
            ..Style::default()
        }
    }
}

/// A brightness factor in 0.85 ..= 1.15 fixed by a strand's index (SplitMix64's finaliser).
fn strand_tint(index: usize) -> f32 {
    let mut z = (index as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    0.85 + 0.3 * ((z >> 40) as f32 / (1u64 << 24) as f32)
}

fn brighten(c: [u8; 3], factor: f32) -> [u8; 3] {
    c.map(|v| (f32::from(v) * factor).round().clamp(0.0, 255.0) as u8)
}

fn colour([r, g, b]: [u8; 3]) -> Color {
    Color::from_rgba8(r, g, b, 255)
}

fn mix(a: [u8; 3], b: [u8; 3], t: f32) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let channel =
        |i: usize| (f32::from(a[i]) + (f32::from(b[i]) - f32::from(a[i])) * t).round() as u8;
    [channel(0), channel(1), channel(2)]
}

/// Number of steps in the root → tip colour ramp.
const SHADES: usize = 32;

/// Fewest colour steps along a strand: a strand with fewer segments is cut into pieces.
const MIN_STEPS: usize = 8;

/// A straight piece of a strand in one colour, in pixels.
struct Piece {
    colour: [u8; 3],
    a: Point,
    b: Point,
}

/// Strokes `pieces` (in strand order), each run of consecutive connected pieces of one colour
/// as one polyline. Small paths matter: tiny-skia fills a stroked outline row by row over its
/// bounding box, so paths gathering far-apart pieces cost far more than many local ones.
fn draw_pieces(pixmap: &mut Pixmap, style: &Style, pieces: &[Piece]) {
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    let stroke = Stroke {
        width: style.strand_width,
        line_cap: LineCap::Round,
        line_join: LineJoin::Round,
        ..Stroke::default()
    };
    for run in pieces.chunk_by(|x, y| x.colour == y.colour && x.b == y.a) {
        paint.set_color(colour(run[0].colour));
        let mut path = PathBuilder::new();
        path.move_to(run[0].a.x, run[0].a.y);
        for piece in run {
            path.line_to(piece.b.x, piece.b.y);
        }
        if let Some(path) = path.finish() {
            pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
}

/// A collider's picture.
enum Solid {
    Disc { centre: Point, radius: f32 },
    Stadium { a: Point, b: Point, radius: f32 },
}

impl Solid {
    fn radius(&self) -> f32 {
        match *self {
            Solid::Disc { radius, .. } | Solid::Stadium { radius, .. } => radius,
        }
    }
}

/// A solid's fill as `gradient` makes it from two stops: the fill's own colour where the light
/// falls (the gradient's start), a third of it on the far side (its end).
fn lit(
    style: &Style,
    gradient: impl FnOnce(Vec<GradientStop>) -> Option<Shader<'static>>,
) -> Shader<'static> {
    let stops = vec![
        GradientStop::new(0.0, colour(brighten(style.collider_fill, 1.05))),
        GradientStop::new(1.0, colour(brighten(style.collider_fill, 0.35))),
    ];
    gradient(stops).unwrap_or(Shader::SolidColor(colour(style.collider_fill)))
}

fn draw_solid(pixmap: &mut Pixmap, style: &Style, solid: &Solid, light: (f32, f32)) {
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    match *solid {
        Solid::Disc { centre, radius } => {
            if let Some(path) = PathBuilder::from_circle(centre.x, centre.y, radius.max(0.5)) {
                let bright = Point::from_xy(
                    centre.x + 0.45 * radius * light.0,
                    centre.y + 0.45 * radius * light.1,
                );
                paint.shader = lit(style, |stops| {
                    let reach = 1.45 * radius.max(0.5);
                    let (mode, at) = (SpreadMode::Pad, Transform::identity());
                    RadialGradient::new(bright, bright, reach, stops, mode, at)
                });
                pixmap.fill_path(
                    &path,
                    &paint,
                    FillRule::Winding,
                    Transform::identity(),
                    None,
                );
                paint.set_color(colour(style.collider_edge));
                let edge = Stroke {
                    width: 1.5,
                    ..Stroke::default()
                };
                pixmap.stroke_path(&path, &paint, &edge, Transform::identity(), None);
            }
        }
        Solid::Stadium { a, b, radius } => {
            // The projection of a capsule is a stroke of its axis with round caps: outline
            // first (a little wider), then the fill.
            let mut path = PathBuilder::new();
            path.move_to(a.x, a.y);
            // A zero-length axis still gets round caps from a tiny nudge.
            path.line_to(b.x + 1e-3, b.y);
            if let Some(path) = path.finish() {
                // Across the axis, toward the light: the lit side of the cylinder.
                let (ax, ay) = (b.x - a.x, b.y - a.y);
                let length = (ax * ax + ay * ay).sqrt().max(1e-6);
                let mut normal = (-ay / length, ax / length);
                if normal.0 * light.0 + normal.1 * light.1 < 0.0 {
                    normal = (-normal.0, -normal.1);
                }
                let middle = Point::from_xy(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
                let side = |k: f32| {
                    Point::from_xy(
                        middle.x + k * radius * normal.0,
                        middle.y + k * radius * normal.1,
                    )
                };
                let fill = lit(style, |stops| {
                    let (mode, at) = (SpreadMode::Pad, Transform::identity());
                    LinearGradient::new(side(0.8), side(-1.0), stops, mode, at)
                });
                for (shader, w) in [
                    (
                        Shader::SolidColor(colour(style.collider_edge)),
                        2.0 * radius + 3.0,
                    ),
                    (fill, 2.0 * radius),
                ] {
                    paint.shader = shader;
                    let stroke = Stroke {
                        width: w.max(1.0),
                        line_cap: LineCap::Round,
                        ..Stroke::default()
                    };
                    pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
                }
            }
        }
    }
}

/// Draws one frame: `strands` (polylines, root first) and `colliders` (world coordinates —
/// move head-attached ones with [`Shape::transformed`] first).
///
/// # Errors
/// A bad size in `camera`.
pub fn render<S: AsRef<[Vec3]>>(
    strands: &[S],
    colliders: &[Shape],
    camera: &Camera,
    style: &Style,
) -> Result<Pixmap, PictureError> {
    let (width, height) = (camera.width, camera.height);
    let mut pixmap = match Pixmap::new(width, height) {
        Some(p) if width <= MAX_SIDE && height <= MAX_SIDE => p,
        _ => {
            return Err(PictureError::BadSize {
                width,
                height,
                max: MAX_SIDE,
            })
        }
    };
    pixmap.fill(colour(style.background));

    // Planes are the ground and walls: behind everything.
    for shape in colliders {
        if let Shape::Plane { point, normal } = *shape {
            draw_plane(&mut pixmap, camera, style, point, normal);
        }
    }

    // Colliders far to near.
    let mut solids: Vec<(f32, Solid)> = Vec::new();
    for shape in colliders {
        match *shape {
            Shape::Sphere { centre, radius } => {
                let (c, depth) = camera.project(centre);
                solids.push((
                    depth,
                    Solid::Disc {
                        centre: c,
                        radius: radius * camera.scale,
                    },
                ));
            }
            Shape::Capsule { a, b, radius } => {
                let ((pa, da), (pb, db)) = (camera.project(a), camera.project(b));
                solids.push((
                    0.5 * (da + db),
                    Solid::Stadium {
                        a: pa,
                        b: pb,
                        radius: radius * camera.scale,
                    },
                ));
            }
            Shape::Plane { .. } => {}
        }
    }
    // Among colliders at the same depth the larger is drawn last: a neck capsule centred in
    // the head's plane is hidden by the head, not drawn over its chin.
    solids.sort_by(|x, y| {
        y.0.total_cmp(&x.0)
            .then_with(|| x.1.radius().total_cmp(&y.1.radius()))
    });

    // Strand pieces are sorted into layers: layer k holds the pieces with k colliders behind
    // them (by midpoint depth), drawn after those k colliders and before the rest. Each piece
    // has one shade of the root → tip ramp (SHADES steps), made a little lighter or darker per
    // strand (a fixed hash of its index) so dense hair shows strands rather than bands.
    let mut layers: Vec<Vec<Piece>> = (0..=solids.len()).map(|_| Vec::new()).collect();
    let hair = volume(strands);
    let view = -camera.view.axes().2;
    let light = {
        let (x, y) = camera.project_direction(LIGHT.normalize());
        let length = (x * x + y * y).sqrt().max(1e-6);
        (x / length, y / length)
    };
    for (index, strand) in strands.iter().enumerate() {
        let strand = strand.as_ref();
        let tint = strand_tint(index);
        let segments = strand.len().saturating_sub(1).max(1);
        // Coarse strands are cut into pieces so the ramp shows at least MIN_STEPS steps; finer
        // strands are not (every piece costs a stroke).
        let pieces = MIN_STEPS.div_ceil(segments);
        for (j, pair) in strand.windows(2).enumerate() {
            if !(pair[0].is_finite() && pair[1].is_finite()) {
                continue;
            }
            let ((a, da), (b, db)) = (camera.project(pair[0]), camera.project(pair[1]));
            let depth = 0.5 * (da + db);
            let tangent = (pair[1] - pair[0]).normalize_or_zero();
            let (factor, white) = shading(tangent, 0.5 * (pair[0] + pair[1]), view, hair);
            let layer = solids.iter().take_while(|(d, _)| *d > depth).count();
            let Some(layer) = layers.get_mut(layer) else {
                continue;
            };
            let at = |u: f32| Point::from_xy(a.x + (b.x - a.x) * u, a.y + (b.y - a.y) * u);
            for q in 0..pieces {
                let (u0, u1) = (q as f32 / pieces as f32, (q + 1) as f32 / pieces as f32);
                let t = (j as f32 + 0.5 * (u0 + u1)) / segments as f32;
                let shade = ((t * SHADES as f32) as usize).min(SHADES - 1);
                let ramp = mix(style.root, style.tip, (shade as f32 + 0.5) / SHADES as f32);
                layer.push(Piece {
                    colour: mix(brighten(ramp, tint * factor), [255; 3], white),
                    a: at(u0),
                    b: at(u1),
                });
            }
        }
    }

    for (k, layer) in layers.iter().enumerate() {
        draw_pieces(&mut pixmap, style, layer);
        if let Some((_, solid)) = solids.get(k) {
            draw_solid(&mut pixmap, style, solid, light);
        }
    }
    Ok(pixmap)
}

/// The plane's trace in the picture: its edge line and its solid side shaded. A plane facing the
/// camera (normal along the view) has no edge to draw and is left out.
fn draw_plane(pixmap: &mut Pixmap, camera: &Camera, style: &Style, point: Vec3, normal: Vec3) {
    let (p, _) = camera.project(point);
    // The normal in pixel space (y down).
    let (nx, ny) = camera.project_direction(normal);
    let n_len = (nx * nx + ny * ny).sqrt();
    if n_len.is_nan() || n_len <= 1e-3 || !p.x.is_finite() || !p.y.is_finite() {
        return;
    }
    let (nx, ny) = (nx / n_len, ny / n_len);
    // Clip the picture's rectangle to the solid side, (q − p)·n ≤ 0 (Sutherland–Hodgman, one edge).
    let (w, h) = (pixmap.width() as f32, pixmap.height() as f32);
    let corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
    let side = |q: (f32, f32)| (q.0 - p.x) * nx + (q.1 - p.y) * ny;
    let mut polygon = Vec::with_capacity(6);
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            polygon.push(a);
        }
        if (sa <= 0.0) != (sb <= 0.0) {
            let t = sa / (sa - sb);
            polygon.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    let mut paint = Paint {
        anti_alias: true,
        ..Paint::default()
    };
    if polygon.len() >= 3 {
        let mut path = PathBuilder::new();
        path.move_to(polygon[0].0, polygon[0].1);
        for q in &polygon[1..] {
            path.line_to(q.0, q.1);
        }
        path.close();
        if let Some(path) = path.finish() {
            paint.set_color(colour(style.plane_fill));
            pixmap.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }
    // The edge: the line through p along (−ny, nx), long enough to cross the picture.
    let reach = w + h;
    let mut path = PathBuilder::new();
    path.move_to(p.x - ny * reach, p.y + nx * reach);
    path.line_to(p.x + ny * reach, p.y - nx * reach);
    if let Some(path) = path.finish() {
        paint.set_color(colour(style.collider_edge));
        let stroke = Stroke {
            width: 2.0,
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
}

/// Draws one frame and encodes it as PNG.
///
/// # Errors
/// A bad size, or PNG encoding.
pub fn render_png<S: AsRef<[Vec3]>>(
    strands: &[S],
    colliders: &[Shape],
    camera: &Camera,
    style: &Style,
) -> Result<Vec<u8>, PictureError> {
    render(strands, colliders, camera, style)?
        .encode_png()
        .map_err(|e| PictureError::Png(e.to_string()))
}

#[cfg(test)]
mod tests;
