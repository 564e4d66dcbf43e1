//! Animated GIF, written a frame at a time.

use std::io::Write;

use gif::{Encoder, Frame, Repeat};
use hairsim_core::{Shape, Vec3};

use super::{render, Camera, PictureError, Style, MAX_SIDE};

/// Writes an animated GIF one frame at a time: memory stays at one frame's pixels whatever the
/// run's length. Every frame uses the same camera (pick one with [`Camera::fit_reach`] so the
/// hair stays in the picture). Colours are quantised per frame (NeuQuant).
pub struct GifWriter<W: Write> {
    encoder: Encoder<W>,
    camera: Camera,
    style: Style,
    delay_centiseconds: u16,
    frames: usize,
}

impl<W: Write> GifWriter<W> {
    /// Starts a looping GIF on `out`; each frame shows for `delay_centiseconds` (GIF's unit).
    ///
    /// # Errors
    /// A bad picture size, or writing the GIF header.
    pub fn new(
        out: W,
        camera: Camera,
        style: Style,
        delay_centiseconds: u16,
    ) -> Result<Self, PictureError> {
        let (width, height) = (camera.width, camera.height);
        let side = |n: u32| {
            u16::try_from(n)
                .ok()
                .filter(|&n| n > 0 && u32::from(n) <= MAX_SIDE)
        };
        let (Some(w), Some(h)) = (side(width), side(height)) else {
            return Err(PictureError::BadSize {
                width,
                height,
                max: MAX_SIDE,
            });
        };
        let mut encoder = Encoder::new(out, w, h, &[])?;
        encoder.set_repeat(Repeat::Infinite)?;
        Ok(GifWriter {
            encoder,
            camera,
            style,
            delay_centiseconds,
            frames: 0,
        })
    }

    /// Draws and appends one frame.
    ///
    /// # Errors
    /// Encoding or writing.
    pub fn add_frame<S: AsRef<[Vec3]>>(
        &mut self,
        strands: &[S],
        colliders: &[Shape],
    ) -> Result<(), PictureError> {
        let pixmap = render(strands, colliders, &self.camera, &self.style)?;
        // The background is opaque, so premultiplied and straight RGBA are the same bytes.
        let mut rgba = pixmap.take();
        // Checked in `new`: both sides fit in u16.
        let (w, h) = (self.camera.width as u16, self.camera.height as u16);
        let mut frame = Frame::from_rgba_speed(w, h, &mut rgba, 10);
        frame.delay = self.delay_centiseconds;
        self.encoder.write_frame(&frame)?;
        self.frames += 1;
        Ok(())
    }

    /// Frames written so far.
    #[must_use]
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Writes the GIF trailer and gives back the writer.
    ///
    /// # Errors
    /// Writing the trailer.
    pub fn finish(self) -> Result<W, PictureError> {
        Ok(self.encoder.into_inner()?)
    }
}
