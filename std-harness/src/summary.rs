//! The summary a run prints: as text for people, as one JSON object for tools.

use serde::Serialize;

/// What `hairsim run` reports.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// `rod` or `dftl`.
    pub solver: String,
    /// Math backend name.
    pub math: String,
    /// Steps run.
    pub steps: u64,
    /// Time step, s.
    pub dt: f32,
    /// Simulated strands.
    pub strands: usize,
    /// Simulated nodes (all strands).
    pub nodes: usize,
    /// State hash after the last step, as `0x` + 16 hex digits.
    pub state_hash: String,
    /// Largest relative stretch of a segment without contact, over the run.
    pub max_stretch: f32,
    /// Deepest node inside a collider after any step, m.
    pub max_penetration: f32,
    /// Whether the final state is finite everywhere.
    pub finite: bool,
    /// Median wall time of one step, ms.
    pub ms_per_step: f64,
    /// Projection iterations summed over the run.
    pub iterations: u64,
    /// Steps × strands whose projection hit its cap.
    pub caps_hit: u64,
    /// Strand roll-backs over the run.
    pub rolled_back: u64,
}

/// Formats a state hash the way every tool prints it.
#[must_use]
pub fn hash_string(hash: u64) -> String {
    format!("0x{hash:016x}")
}

impl Summary {
    /// The summary as one line of JSON.
    #[must_use]
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a summary always serialises")
    }

    /// The summary for people.
    #[must_use]
    pub fn to_text(&self) -> String {
        format!(
            "scene       {}\nsolver      {} ({} math)\nsteps       {} x {} s\nstrands     {} ({} nodes)\nstate hash  {}\nmax stretch {:.3e}\nmax depth   {:.3e} m\nfinite      {}\nstep time   {:.4} ms (median)\niterations  {} (caps hit {}, rolled back {})",
            self.scene,
            self.solver,
            self.math,
            self.steps,
            self.dt,
            self.strands,
            self.nodes,
            self.state_hash,
            self.max_stretch,
            self.max_penetration,
            self.finite,
            self.ms_per_step,
            self.iterations,
            self.caps_hit,
            self.rolled_back
        )
    }
}
