//! The parameters of the SPH hair–hair stage (scene section `[hair_hair]`): what a scene sets
//! and checks. The stage itself is `hairsim::sph`, which re-exports these.

/// The largest neighbour cap a scene may set.
pub const MAX_CAP: usize = 256;

/// SPH parameters (scene section `[hair_hair]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphParams {
    /// Smoothing length `h`, m: the kernel radius and the grid's cell size.
    pub smoothing_length: f32,
    /// Rest density `ρ₀`, kg/m³: below it there is no pressure (repulsion only).
    pub rest_density: f32,
    /// Pressure stiffness `k` in `p = k (ρ − ρ₀)`, m²/s² (the paper's repulsion, in [0, 0.5]).
    pub stiffness: f32,
    /// Viscosity `µ`, the strand-to-strand friction (the paper's range [0, 200]).
    pub viscosity: f32,
    /// Most neighbours kept per node; further ones are dropped (counted in the stats).
    pub neighbour_cap: usize,
    /// Nodes of the same strand within this many indices are not neighbours: without it a
    /// strand pushes itself apart.
    pub same_strand_gap: u32,
}

impl Default for SphParams {
    fn default() -> Self {
        SphParams {
            smoothing_length: 0.01,
            rest_density: 2.0,
            stiffness: 0.2,
            viscosity: 20.0,
            neighbour_cap: 24,
            same_strand_gap: 3,
        }
    }
}

impl SphParams {
    /// Checks every parameter; the error names the field and what is allowed.
    pub fn validate(&self) -> Result<(), String> {
        let check = |ok: bool, what: &str| if ok { Ok(()) } else { Err(what.to_string()) };
        check(
            self.smoothing_length.is_finite() && (1e-4..=1.0).contains(&self.smoothing_length),
            "smoothing_length: allowed 1e-4 to 1 m",
        )?;
        check(
            self.rest_density.is_finite() && self.rest_density >= 0.0,
            "rest_density: allowed a finite value >= 0 kg/m3",
        )?;
        check(
            self.stiffness.is_finite() && (0.0..=0.5).contains(&self.stiffness),
            "stiffness: allowed 0 to 0.5",
        )?;
        check(
            self.viscosity.is_finite() && (0.0..=200.0).contains(&self.viscosity),
            "viscosity: allowed 0 to 200",
        )?;
        check(
            (1..=MAX_CAP).contains(&self.neighbour_cap),
            "neighbour_cap: allowed 1 to 256",
        )?;
        check(
            self.same_strand_gap <= 64,
            "same_strand_gap: allowed 0 to 64",
        )
    }
}
