//! What `--out DIR` writes, through the `export` module's [`OutDir`]: frames every K steps in
//! the scene's formats (leaders and the followers drawn around them), a GIF of them when the
//! scene asks, and always `final.obj` and `final.png`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use hairsim_core::{Collider, Pose, Shape, Strand, Vec3};

use crate::export::{Format, OutDir, OutOptions};
use crate::picture::View;
use crate::scene::generate::Follower;
use crate::scene::prepare::OutputPlan;
use crate::scene::Prepared;

/// The export module's options for an output plan; `every` is whether frames are written.
#[must_use]
pub fn out_options(plan: &OutputPlan, frames: bool) -> OutOptions {
    let frame_formats = if frames {
        plan.formats
            .iter()
            .filter_map(|name| Format::ALL.into_iter().find(|f| f.extension() == name))
            .collect()
    } else {
        Vec::new()
    };
    OutOptions {
        frame_formats,
        view: match plan.view.as_str() {
            "back" => View::Back,
            "side" => View::Side,
            "top" => View::Top,
            _ => View::Front,
        },
        picture_size: (plan.width, plan.height),
        gif: plan.picture == "gif",
        ..OutOptions::default()
    }
}

/// Every strand drawn, root to tip: the leaders, then the followers (`copy_leader`).
#[must_use]
pub fn polylines<const N: usize>(
    strands: &[Strand<N>],
    followers: &[Follower],
    head: &Pose,
) -> Vec<Vec<Vec3>> {
    let mut lines: Vec<Vec<Vec3>> = strands.iter().map(|s| s.positions().to_vec()).collect();
    for f in followers {
        if let Some(leader) = strands.get(f.leader as usize) {
            let mut line = vec![Vec3::ZERO; leader.nodes()];
            hairsim_core::follow::copy_leader(leader.positions(), head, f.offset, &mut line);
            lines.push(line);
        }
    }
    lines
}

/// The colliders where they are (attached ones moved with the head).
#[must_use]
pub fn placed(colliders: &[Collider], head: &Pose) -> Vec<Shape> {
    colliders
        .iter()
        .map(|c| {
            if c.attached_to_head {
                c.shape.transformed(head)
            } else {
                c.shape
            }
        })
        .collect()
}

/// Frames written during a run.
pub struct Frames {
    out: OutDir,
    dir: PathBuf,
    every: Option<u64>,
    followers: Vec<Follower>,
    colliders: Vec<Collider>,
}

impl Frames {
    /// Prepares `dir` (created if missing). Frames every `every` steps (`--every`, else the
    /// scene's `output.every`); a GIF without either gets 100 frames over the run.
    pub fn new(dir: &Path, prepared: &Prepared, every: Option<u64>, steps: u64) -> Result<Frames> {
        let plan = &prepared.output;
        let every = every.or(plan.every);
        let gif_every = (plan.picture == "gif").then(|| (steps / 100).max(1));
        let out = OutDir::create(dir, out_options(plan, every.is_some()))
            .with_context(|| format!("--out {}", dir.display()))?;
        Ok(Frames {
            out,
            dir: dir.to_path_buf(),
            every: every.or(gif_every),
            followers: if plan.followers {
                prepared.followers.clone()
            } else {
                Vec::new()
            },
            colliders: prepared.colliders.clone(),
        })
    }

    /// Writes a frame when `done` is a multiple of `every`.
    pub fn after_step<const N: usize>(
        &mut self,
        done: u64,
        strands: &[Strand<N>],
        head: &Pose,
    ) -> Result<()> {
        if self.every.is_some_and(|k| done % k == 0) {
            let lines = polylines(strands, &self.followers, head);
            self.out
                .frame(done, &lines, &placed(&self.colliders, head))
                .with_context(|| format!("--out {}: frame {done}", self.dir.display()))?;
        }
        Ok(())
    }

    /// Writes `final.obj`, `final.png` and closes the GIF; returns every file written.
    pub fn finish<const N: usize>(
        self,
        strands: &[Strand<N>],
        head: &Pose,
    ) -> Result<Vec<PathBuf>> {
        let lines = polylines(strands, &self.followers, head);
        let dir = self.dir.clone();
        self.out
            .finish(&lines, &placed(&self.colliders, head))
            .with_context(|| format!("--out {}", dir.display()))
    }
}
