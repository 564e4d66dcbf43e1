//! Record and replay.
//!
//! A recording holds the scene (as scene-file text), the build identity, every time-varying
//! input (the head pose and the grab targets and releases of every step) and the state hash
//! every `every` steps. `hairsim replay` runs the scene again *from the recorded inputs* and
//! fails at the first checkpoint whose hash differs, naming the step and both hashes.
//!
//! File format, version [`VERSION`]: the magic line [`MAGIC`], then one JSON object
//! ([`Recording`]). Floats are stored as JSON numbers, which round-trip `f32` exactly. A
//! recording of a newer version, or from a build with another identity (crate version, math
//! backend, capacities), is refused before anything runs.

use std::path::Path;

use anyhow::{bail, Context, Result};
use hairsim_core::math::Quat;
use hairsim_core::{Math, Pose, Vec3};
use serde::{Deserialize, Serialize};

use crate::sim::StepInputs;

/// First line of every recording.
pub const MAGIC: &str = "HAIRSIM-RECORDING";
/// The recording format this build writes and reads.
pub const VERSION: u32 = 1;
/// The strand capacities this build monomorphises: two, since each one compiles the whole
/// simulation again (the DFTL block pass alone eight ways). 32 holds every built-in scene (at
/// most 30 nodes), 128 any scene file. The state hash does not depend on the capacity (it
/// hashes the strands' nodes only); the cost does a little: a scene of 16-node strands takes
/// 0.3 to 14 % more instructions at 32 than it did at 16.
pub const CAPACITIES: [usize; 2] = [32, 128];

/// What must match for a recording to replay bit for bit.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildIdentity {
    /// `hairsim` crate version.
    pub version: String,
    /// Math backend name.
    pub math: String,
    /// Strand capacities of this build.
    pub capacities: Vec<usize>,
    /// Most colliders and grabs the core holds.
    pub max_colliders: usize,
    /// Most grabs.
    pub max_grabs: usize,
}

impl BuildIdentity {
    /// This build's identity with math backend `M`.
    #[must_use]
    pub fn current<M: Math>() -> BuildIdentity {
        BuildIdentity {
            version: env!("CARGO_PKG_VERSION").into(),
            math: M::NAME.into(),
            capacities: CAPACITIES.to_vec(),
            max_colliders: hairsim_core::collide::MAX_COLLIDERS,
            max_grabs: hairsim_core::grab::MAX_GRABS,
        }
    }
}

/// One step's inputs as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordedInputs {
    /// Head position x, y, z, then rotation x, y, z, w.
    pub head: [f32; 7],
    /// Grab targets, m.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grabs: Vec<[f32; 3]>,
    /// Grabs let go.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub released: Vec<bool>,
}

impl RecordedInputs {
    /// Stores `inputs`.
    #[must_use]
    pub fn from_inputs(inputs: &StepInputs) -> RecordedInputs {
        let (p, q) = (inputs.head.position, inputs.head.rotation);
        RecordedInputs {
            head: [p.x, p.y, p.z, q.x, q.y, q.z, q.w],
            grabs: inputs.grab_targets.iter().map(|t| t.to_array()).collect(),
            released: inputs.released.clone(),
        }
    }

    /// The inputs as the simulation takes them.
    #[must_use]
    pub fn to_inputs(&self) -> StepInputs {
        let h = self.head;
        StepInputs {
            head: Pose {
                position: Vec3::new(h[0], h[1], h[2]),
                rotation: Quat::from_xyzw(h[3], h[4], h[5], h[6]),
            },
            grab_targets: self.grabs.iter().map(|t| Vec3::from_array(*t)).collect(),
            released: self.released.clone(),
        }
    }
}

/// The state hash after a number of steps.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// Steps taken when the hash was computed.
    pub step: u64,
    /// The state hash, `0x` + 16 hex digits.
    pub hash: String,
}

/// A recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recording {
    /// Format version.
    pub version: u32,
    /// The build that recorded it.
    pub build: BuildIdentity,
    /// Where the scene came from (file or `builtin:NAME`).
    pub source: String,
    /// The scene, as scene-file text.
    pub scene: String,
    /// The strand capacity the run used.
    pub capacity: usize,
    /// A checkpoint every this many steps.
    pub every: u64,
    /// The inputs of every step, in order.
    pub inputs: Vec<RecordedInputs>,
    /// The checkpoints, in order (the last one after the last step).
    pub checkpoints: Vec<Checkpoint>,
}

impl Recording {
    /// Writes the recording to `path`.
    pub fn write(&self, path: &Path) -> Result<()> {
        let json = serde_json::to_string(self).context("serialising the recording")?;
        std::fs::write(path, format!("{MAGIC}\n{json}\n"))
            .with_context(|| format!("cannot write the recording {}", path.display()))
    }

    /// Reads a recording, refusing (before anything runs) files without the magic, of a newer
    /// version, or from a build with another identity than `expected`.
    pub fn read(path: &Path, expected: &BuildIdentity) -> Result<Recording> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the recording {}", path.display()))?;
        Recording::parse(&text, expected).with_context(|| format!("{}", path.display()))
    }

    /// Parses recording text (see [`Recording::read`]).
    pub fn parse(text: &str, expected: &BuildIdentity) -> Result<Recording> {
        let Some(body) = text.strip_prefix(MAGIC).and_then(|t| t.strip_prefix('\n')) else {
            bail!("not a hairsim recording: the first line is not {MAGIC}");
        };
        // Look at the version and the build before anything else, so a newer file is refused
        // for what it is and not for a field this build does not know.
        let header: serde_json::Value =
            serde_json::from_str(body).context("the recording is damaged: not one JSON object")?;
        let version = header.get("version").and_then(serde_json::Value::as_u64);
        match version {
            Some(v) if v == u64::from(VERSION) => {}
            Some(v) if v > u64::from(VERSION) => bail!(
                "recording format {v} is newer than this build reads (format {VERSION}): replay it with the build that wrote it or a newer one"
            ),
            Some(v) => bail!("recording format {v} is not readable by this build (format {VERSION} only)"),
            None => bail!("the recording is damaged: no format version"),
        }
        let build: BuildIdentity =
            serde_json::from_value(header.get("build").cloned().unwrap_or_default())
                .context("the recording is damaged: no build identity")?;
        if &build != expected {
            bail!(
                "recorded by another build ({}), this build is ({}): the same bits are not promised, so it is refused",
                describe(&build),
                describe(expected)
            );
        }
        let recording: Recording =
            serde_json::from_value(header).context("the recording is damaged")?;
        if recording.every == 0 {
            bail!("the recording is damaged: every = 0");
        }
        Ok(recording)
    }
}

fn describe(b: &BuildIdentity) -> String {
    format!(
        "hairsim {}, {} math, capacities {:?}, {} colliders, {} grabs",
        b.version, b.math, b.capacities, b.max_colliders, b.max_grabs
    )
}
