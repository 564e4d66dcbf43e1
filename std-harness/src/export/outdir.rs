//! Everything `hairsim run --out DIR` writes, in one place.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use hairsim_core::{Shape, Vec3};

use super::{ExportError, Format, DEFAULT_WIDTH};
use crate::picture::{render_png, Camera, GifWriter, Style, View};

/// What an [`OutDir`] writes besides `final.obj` and `final.png`.
#[derive(Clone, Debug, PartialEq)]
pub struct OutOptions {
    /// Formats for `DIR/frames/frame_NNNNNN.EXT` on every [`OutDir::frame`] call (empty: none).
    pub frame_formats: Vec<Format>,
    /// Strand diameter written where a format has one, m.
    pub strand_width: f32,
    /// Camera direction for the pictures.
    pub view: View,
    /// Picture size in pixels, `(width, height)`.
    pub picture_size: (u32, u32),
    /// Whether [`OutDir::frame`] also appends to `DIR/run.gif`.
    pub gif: bool,
    /// Time each GIF frame shows, in centiseconds (GIF's unit).
    pub gif_delay_centiseconds: u16,
    /// GIF size in pixels (smaller than the still: a GIF frame is quantised and kept whole).
    pub gif_size: (u32, u32),
    /// The GIF's camera (its size wins over `gif_size`); `None`: [`Camera::fit_reach`] of the
    /// first frame, which keeps inextensible strands with fixed roots in the picture.
    pub gif_camera: Option<Camera>,
    /// Colours and widths; `None`: [`Style::for_strand_count`] of the first frame drawn.
    pub style: Option<Style>,
}

impl Default for OutOptions {
    fn default() -> Self {
        OutOptions {
            frame_formats: Vec::new(),
            strand_width: DEFAULT_WIDTH,
            view: View::Front,
            picture_size: (800, 800),
            gif: true,
            gif_delay_centiseconds: 4,
            gif_size: (400, 400),
            gif_camera: None,
            style: None,
        }
    }
}

/// An output directory filled as a run goes:
///
/// ```no_run
/// # use hairsim::export::{OutDir, OutOptions, Format};
/// # let frames: Vec<Vec<Vec<hairsim::core::Vec3>>> = vec![Vec::new()];
/// # let colliders: [hairsim::core::Shape; 0] = [];
/// let mut out = OutDir::create("out", OutOptions { frame_formats: vec![Format::Obj], ..OutOptions::default() })?;
/// for (step, strands) in frames.iter().enumerate() {
///     out.frame(step as u64, strands, &colliders)?; // frames/frame_000000.obj, a run.gif frame
/// }
/// let written = out.finish(&frames[frames.len() - 1], &colliders)?; // final.obj, final.png, run.gif
/// # Ok::<(), hairsim::export::ExportError>(())
/// ```
///
/// Colliders are in world coordinates (move head-attached ones with `Shape::transformed`).
pub struct OutDir {
    dir: PathBuf,
    options: OutOptions,
    gif: Option<GifWriter<BufWriter<File>>>,
    written: Vec<PathBuf>,
}

impl OutDir {
    /// Creates `dir` (and `dir/frames` when frames are written).
    ///
    /// # Errors
    /// I/O.
    pub fn create(dir: impl AsRef<Path>, options: OutOptions) -> Result<OutDir, ExportError> {
        let dir = dir.as_ref().to_path_buf();
        std::fs::create_dir_all(&dir)?;
        if !options.frame_formats.is_empty() {
            std::fs::create_dir_all(dir.join("frames"))?;
        }
        Ok(OutDir {
            dir,
            options,
            gif: None,
            written: Vec::new(),
        })
    }

    /// The path of frame `step` in `format`: `DIR/frames/frame_{step:06}.EXT`.
    #[must_use]
    pub fn frame_path(&self, step: u64, format: Format) -> PathBuf {
        self.dir
            .join("frames")
            .join(format!("frame_{step:06}.{}", format.extension()))
    }

    /// Writes frame `step` in every frame format and appends it to `run.gif`. The GIF's camera
    /// is fixed at the first frame to cover everywhere its strands can reach.
    ///
    /// # Errors
    /// I/O, what a writer refuses (TressFX needs equal strand lengths), or GIF encoding.
    pub fn frame<S: AsRef<[Vec3]>>(
        &mut self,
        step: u64,
        strands: &[S],
        colliders: &[Shape],
    ) -> Result<(), ExportError> {
        for &format in &self.options.frame_formats {
            let path = self.frame_path(step, format);
            format.write(File::create(&path)?, strands, self.options.strand_width)?;
            self.written.push(path);
        }
        if self.options.gif {
            if self.gif.is_none() {
                let (w, h) = self.options.gif_size;
                let camera = self.options.gif_camera.unwrap_or_else(|| {
                    Camera::fit_reach(strands, colliders, self.options.view, w, h)
                });
                let path = self.dir.join("run.gif");
                let file = BufWriter::new(File::create(&path)?);
                self.gif = Some(GifWriter::new(
                    file,
                    camera,
                    self.style(strands.len()),
                    self.options.gif_delay_centiseconds,
                )?);
                self.written.push(path);
            }
            if let Some(gif) = &mut self.gif {
                gif.add_frame(strands, colliders)?;
            }
        }
        Ok(())
    }

    fn style(&self, strands: usize) -> Style {
        self.options
            .style
            .unwrap_or_else(|| Style::for_strand_count(strands))
    }

    /// Writes `final.obj` and `final.png` (camera fitted to this frame) and closes `run.gif`.
    /// Returns every file written, in order.
    ///
    /// # Errors
    /// I/O, a writer's refusal, or picture encoding.
    pub fn finish<S: AsRef<[Vec3]>>(
        mut self,
        strands: &[S],
        colliders: &[Shape],
    ) -> Result<Vec<PathBuf>, ExportError> {
        let obj = self.dir.join("final.obj");
        Format::Obj.write(File::create(&obj)?, strands, self.options.strand_width)?;
        self.written.push(obj);
        let (w, h) = self.options.picture_size;
        let camera = Camera::fit_frame(strands, colliders, self.options.view, w, h);
        let png = self.dir.join("final.png");
        let style = self.style(strands.len());
        std::fs::write(&png, render_png(strands, colliders, &camera, &style)?)?;
        self.written.push(png);
        if let Some(gif) = self.gif.take() {
            let mut file = gif.finish()?;
            std::io::Write::flush(&mut file)?;
        }
        Ok(self.written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::read_obj;

    #[test]
    fn out_dir_writes_frames_final_obj_png_and_gif() {
        let dir = std::env::temp_dir().join(format!("hairsim-outdir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let options = OutOptions {
            frame_formats: Format::ALL.to_vec(),
            picture_size: (120, 90),
            gif_size: (60, 45),
            ..OutOptions::default()
        };
        let head = [Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 0.05,
        }];
        let strand = |k: u64| -> Vec<Vec<Vec3>> {
            vec![
                (0..6)
                    .map(|i| Vec3::new(0.05 + 0.001 * k as f32, -0.02 * i as f32, 0.0))
                    .collect();
                2
            ]
        };
        let mut out = OutDir::create(&dir, options).unwrap();
        for step in [0, 10, 20] {
            out.frame(step, &strand(step), &head).unwrap();
        }
        let written = out.finish(&strand(20), &head).unwrap();
        assert_eq!(written.len(), 3 * 5 + 1 + 2);
        for path in &written {
            assert!(
                std::fs::metadata(path).unwrap().len() > 0,
                "{}",
                path.display()
            );
        }
        assert!(dir.join("frames/frame_000010.usda").exists());
        let text = std::fs::read_to_string(dir.join("final.obj")).unwrap();
        assert_eq!(read_obj(&text).unwrap(), strand(20));
        let gif = std::fs::read(dir.join("run.gif")).unwrap();
        assert_eq!(&gif[..6], b"GIF89a");
        assert_eq!(gif.last(), Some(&0x3B), "GIF trailer written");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
