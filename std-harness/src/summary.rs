//! The summary a run prints: as text for people, as one JSON object for tools.

use serde::Serialize;

use crate::groom::Groom;

/// What `hairsim run` reports.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// `rod` or `dftl`.
    pub solver: String,
    /// Math backend name.
    pub math: String,
    /// The effects that ran, by name.
    pub effects: Vec<String>,
    /// Steps run.
    pub steps: u64,
    /// Time step, s.
    pub dt: f32,
    /// Simulated strands.
    pub strands: usize,
    /// Simulated nodes (all strands).
    pub nodes: usize,
    /// Follower strands (drawn, not simulated).
    pub followers: usize,
    /// Node capacity the run was built with.
    pub capacity: usize,
    /// Strands per block.
    pub block: usize,
    /// Threads used.
    pub threads: usize,
    /// State hash after the last step, as `0x` + 16 hex digits.
    pub state_hash: String,
    /// Largest relative stretch of a segment without contact, over the run.
    pub max_stretch: f32,
    /// Deepest node inside a collider after any step, m.
    pub max_penetration: f32,
    /// Whether the final state is finite everywhere.
    pub finite: bool,
    /// The simulated strands' groom at the end against their rest groom: mean turning angle
    /// and the share of kinked nodes ([`crate::groom`]).
    pub groom: Groom,
    /// Median wall time of one step, ms.
    pub ms_per_step: f64,
    /// Projection iterations summed over the run.
    pub iterations: u64,
    /// Steps × strands whose projection hit its cap.
    pub caps_hit: u64,
    /// Strand roll-backs over the run.
    pub rolled_back: u64,
    /// Each grab's force after the last step, N (only with grabs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grab_forces: Option<Vec<[f32; 3]>>,
    /// Each grab's status after the last step: held, slipped or released (only with grabs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grab_status: Option<Vec<String>>,
    /// SPH neighbours per node per step, on average (only with `hair-hair`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sph_neighbours: Option<f64>,
    /// Neighbours the SPH cap dropped, over the run (only with `hair-hair`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sph_truncated: Option<u64>,
    /// The hair file the scene read, with the scale and up axis it was read with (only with
    /// a hair file).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hair_file: Option<HairFileUsed>,
    /// Files written by `--out` (empty without it).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub written: Vec<String>,
    /// Each collider's total contact force after the last step, N (only with colliders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collider_forces: Option<Vec<[f32; 3]>>,
}

/// A hair file as a run read it.
#[derive(Clone, Debug, Serialize)]
pub struct HairFileUsed {
    /// The file's path.
    pub path: String,
    /// Factor from the file's units to metres.
    pub scale: f32,
    /// The file's up axis, `y` or `z`.
    pub up: String,
}

/// Formats a state hash the way every tool prints it.
#[must_use]
pub fn hash_string(hash: u64) -> String {
    format!("0x{hash:016x}")
}

fn vectors(v: &[[f32; 3]]) -> String {
    v.iter()
        .map(|f| format!("[{:.3e}, {:.3e}, {:.3e}]", f[0], f[1], f[2]))
        .collect::<Vec<_>>()
        .join(" ")
}

impl Summary {
    /// The summary as one line of JSON.
    #[must_use]
    pub fn to_json(&self) -> String {
        // Plain fields only; f32 non-finite values become `null`, never an error.
        serde_json::to_string(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    /// The summary for people.
    #[must_use]
    pub fn to_text(&self) -> String {
        let mut text = format!(
            "scene       {}\nsolver      {} ({} math)\neffects     {}\nsteps       {} x {} s\nstrands     {} ({} nodes, capacity {}), {} followers\nthreads     {} (blocks of {} strands)\nstate hash  {}\nmax stretch {:.3e}\nmax depth   {:.3e} m\nfinite      {}\nstep time   {:.4} ms (median)\niterations  {} (caps hit {}, rolled back {})",
            self.scene,
            self.solver,
            self.math,
            self.effects.join(", "),
            self.steps,
            self.dt,
            self.strands,
            self.nodes,
            self.capacity,
            self.followers,
            self.threads,
            self.block,
            self.state_hash,
            self.max_stretch,
            self.max_penetration,
            self.finite,
            self.ms_per_step,
            self.iterations,
            self.caps_hit,
            self.rolled_back
        );
        text.push_str(&format!(
            "\ngroom       mean turning {:.3} rad (rest {:.3}), kinked {:.2} % of {} nodes",
            self.groom.mean_turning,
            self.groom.rest_mean_turning,
            100.0 * self.groom.kinked,
            self.groom.nodes
        ));
        if let (Some(forces), Some(status)) = (&self.grab_forces, &self.grab_status) {
            text.push_str(&format!(
                "\ngrabs       {} ({})",
                vectors(forces),
                status.join(", ")
            ));
        }
        if let Some(forces) = &self.collider_forces {
            text.push_str(&format!("\ncolliders   {}", vectors(forces)));
        }
        if let (Some(mean), Some(truncated)) = (self.sph_neighbours, self.sph_truncated) {
            text.push_str(&format!(
                "\nhair-hair   {mean:.1} neighbours per node, {truncated} dropped by the cap"
            ));
        }
        if let Some(file) = &self.hair_file {
            text.push_str(&format!(
                "\nhair file   {} (scale {:.4e} to metres, {}-up)",
                file.path, file.scale, file.up
            ));
        }
        if let Some(last) = self.written.last() {
            text.push_str(&format!(
                "\nwritten     {} files, last {last}",
                self.written.len()
            ));
        }
        text
    }
}
