//! The orthographic camera.

use hairsim_core::{Shape, Vec3};
use tiny_skia::Point;

use crate::hairfile::bounds_of;

/// Which way the camera looks. hairsim's world is Y-up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// From +Z looking along −Z: X to the right, Y up.
    #[default]
    Front,
    /// From −Z looking along +Z: −X to the right, Y up.
    Back,
    /// From +X looking along −X: −Z to the right, Y up.
    Side,
    /// From +Y looking down: X to the right, −Z up.
    Top,
}

impl View {
    /// `(right, up, forward)`: the picture's axes and the view direction (away from the camera).
    #[must_use]
    pub fn axes(self) -> (Vec3, Vec3, Vec3) {
        match self {
            View::Front => (Vec3::X, Vec3::Y, Vec3::NEG_Z),
            View::Back => (Vec3::NEG_X, Vec3::Y, Vec3::Z),
            View::Side => (Vec3::NEG_Z, Vec3::Y, Vec3::NEG_X),
            View::Top => (Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y),
        }
    }
}

impl std::str::FromStr for View {
    type Err = String;

    /// `front`, `back`, `side` or `top` (for command-line options).
    fn from_str(name: &str) -> Result<View, String> {
        match name.to_ascii_lowercase().as_str() {
            "front" => Ok(View::Front),
            "back" => Ok(View::Back),
            "side" => Ok(View::Side),
            "top" => Ok(View::Top),
            _ => Err(format!("unknown view {name:?} (front, back, side or top)")),
        }
    }
}

/// An orthographic camera and the picture's size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Which way it looks.
    pub view: View,
    /// The world point shown at the picture's centre.
    pub centre: Vec3,
    /// Pixels per world unit (per metre in hairsim's world).
    pub scale: f32,
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
}

/// Fraction of the picture left empty on each side by the fitting constructors.
pub const MARGIN: f32 = 0.06;

impl Camera {
    /// Fits the box `(min, max)` in a `width`×`height` picture with a [`MARGIN`] on every side,
    /// keeping the aspect ratio. A flat or empty box gets a 1-unit (1 m) frame.
    #[must_use]
    pub fn fit(bounds: (Vec3, Vec3), view: View, width: u32, height: u32) -> Camera {
        let (right, up, _) = view.axes();
        let (min, max) = bounds;
        let size = (max - min).abs();
        // Extent along the picture's axes (the axes are unit world axes, so |·| picks one).
        let along = |axis: Vec3| size.dot(axis.abs());
        let (du, dv) = (along(right), along(up));
        let usable = |pixels: u32| (pixels as f32 * (1.0 - 2.0 * MARGIN)).max(1.0);
        let fit = |pixels: u32, extent: f32| {
            if extent > 0.0 && extent.is_finite() {
                usable(pixels) / extent
            } else {
                f32::INFINITY
            }
        };
        let mut scale = fit(width, du).min(fit(height, dv));
        if !scale.is_finite() {
            scale = usable(width).min(usable(height));
        }
        let centre = 0.5 * (min + max);
        Camera {
            view,
            centre: if centre.is_finite() {
                centre
            } else {
                Vec3::ZERO
            },
            scale,
            width,
            height,
        }
    }

    /// Fits the strands and the bounded colliders (spheres, capsules; planes are unbounded).
    #[must_use]
    pub fn fit_frame<S: AsRef<[Vec3]>>(
        strands: &[S],
        colliders: &[Shape],
        view: View,
        width: u32,
        height: u32,
    ) -> Camera {
        let bounds = union(bounds_of(strands), collider_bounds(colliders));
        Camera::fit(
            bounds.unwrap_or((Vec3::ZERO, Vec3::ZERO)),
            view,
            width,
            height,
        )
    }

    /// Fits every place the strands can reach from their roots (a ball of the strand's length
    /// around each root) and the colliders: a camera that stays right for a whole run of
    /// inextensible strands whose roots stay put, so animation frames do not jump.
    #[must_use]
    pub fn fit_reach<S: AsRef<[Vec3]>>(
        strands: &[S],
        colliders: &[Shape],
        view: View,
        width: u32,
        height: u32,
    ) -> Camera {
        let mut bounds = collider_bounds(colliders);
        for strand in strands {
            let strand = strand.as_ref();
            if let Some(&root) = strand.first() {
                let length = crate::hairfile::polyline_length(strand);
                if root.is_finite() && length.is_finite() {
                    bounds = union(
                        bounds,
                        Some((root - Vec3::splat(length), root + Vec3::splat(length))),
                    );
                }
            }
        }
        Camera::fit(
            bounds.unwrap_or((Vec3::ZERO, Vec3::ZERO)),
            view,
            width,
            height,
        )
    }

    /// Pixel position (y down) and depth along the view direction (larger is farther).
    #[must_use]
    pub fn project(&self, p: Vec3) -> (Point, f32) {
        let (right, up, forward) = self.view.axes();
        let d = p - self.centre;
        let x = 0.5 * self.width as f32 + d.dot(right) * self.scale;
        let y = 0.5 * self.height as f32 - d.dot(up) * self.scale;
        (Point::from_xy(x, y), p.dot(forward))
    }

    /// A direction in pixel space (y down), scaled by [`Camera::scale`].
    #[must_use]
    pub fn project_direction(&self, v: Vec3) -> (f32, f32) {
        let (right, up, _) = self.view.axes();
        (v.dot(right) * self.scale, -v.dot(up) * self.scale)
    }
}

fn collider_bounds(colliders: &[Shape]) -> Option<(Vec3, Vec3)> {
    colliders.iter().fold(None, |acc, shape| {
        let b = match *shape {
            Shape::Sphere { centre, radius } => {
                Some((centre - Vec3::splat(radius), centre + Vec3::splat(radius)))
            }
            Shape::Capsule { a, b, radius } => Some((
                a.min(b) - Vec3::splat(radius),
                a.max(b) + Vec3::splat(radius),
            )),
            Shape::Plane { .. } => None,
        };
        union(acc, b.filter(|(lo, hi)| lo.is_finite() && hi.is_finite()))
    })
}

fn union(a: Option<(Vec3, Vec3)>, b: Option<(Vec3, Vec3)>) -> Option<(Vec3, Vec3)> {
    match (a, b) {
        (Some((a0, a1)), Some((b0, b1))) => Some((a0.min(b0), a1.max(b1))),
        (x, None) | (None, x) => x,
    }
}
