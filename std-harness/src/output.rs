//! What `--out DIR` writes: frames (leaders and the followers drawn around them) and pictures.
//!
//! Hook point: the writers (OBJ, PLY, `.hair`, USDA) and pictures (PNG, GIF) belong to the
//! `export` module. [`Frames`] assembles each frame's polylines here; [`check`] refuses `--out`
//! with a clear message for as long as the writers are not part of this build, before anything
//! runs.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use hairsim_core::{Pose, Strand, Vec3};

use crate::scene::generate::Follower;
use crate::scene::prepare::OutputPlan;
use crate::scene::Prepared;

/// Refuses an output folder this build cannot fill.
pub fn check(dir: &Path, plan: &OutputPlan) -> Result<()> {
    bail!(
        "--out {}: frames ({}) and pictures ({}) arrive with the export module, which this build does not have yet; run without --out",
        dir.display(),
        plan.formats.join(", "),
        plan.picture
    )
}

/// One frame: every strand drawn, root to tip — the leaders, then the followers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Steps taken.
    pub step: u64,
    /// Polylines, m (world frame).
    pub strands: Vec<Vec<Vec3>>,
}

/// Assembles a frame from the simulated strands and the followers.
#[must_use]
pub fn frame<const N: usize>(
    step: u64,
    strands: &[Strand<N>],
    followers: &[Follower],
    head: &Pose,
) -> Frame {
    let mut lines: Vec<Vec<Vec3>> = strands.iter().map(|s| s.positions().to_vec()).collect();
    for f in followers {
        if let Some(leader) = strands.get(f.leader as usize) {
            let offset = head.transform_vector(f.offset);
            lines.push(leader.positions().iter().map(|p| *p + offset).collect());
        }
    }
    Frame {
        step,
        strands: lines,
    }
}

/// Frames written during a run.
#[derive(Clone, Debug)]
pub struct Frames {
    dir: PathBuf,
    every: Option<u64>,
    followers: Vec<Follower>,
    frames: Vec<Frame>,
}

impl Frames {
    /// Prepares to write into `dir` (created if missing).
    pub fn new(dir: &Path, prepared: &Prepared, every: Option<u64>) -> Result<Frames> {
        check(dir, &prepared.output)?;
        Ok(Frames {
            dir: dir.to_path_buf(),
            every: every.or(prepared.output.every),
            followers: if prepared.output.followers {
                prepared.followers.clone()
            } else {
                Vec::new()
            },
            frames: Vec::new(),
        })
    }

    /// Keeps a frame every `every` steps.
    pub fn after_step<const N: usize>(
        &mut self,
        done: u64,
        _steps: u64,
        strands: &[Strand<N>],
        head: &Pose,
    ) -> Result<()> {
        if self.every.is_some_and(|k| done % k == 0) {
            self.frames
                .push(frame(done, strands, &self.followers, head));
        }
        Ok(())
    }

    /// Writes the frames and the final frame.
    pub fn finish<const N: usize>(self, strands: &[Strand<N>], head: &Pose) -> Result<()> {
        let last = frame(0, strands, &self.followers, head);
        bail!(
            "{}: cannot write {} frames and the final one ({} strands): the export module is not part of this build",
            self.dir.display(),
            self.frames.len(),
            last.strands.len()
        )
    }
}
