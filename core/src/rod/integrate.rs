//! Kmoch 2009 Algorithm 1 line 4, "integrate equations of motion", explicitly: symplectic
//! Euler `v ← v + h F/m`, then `x ← x + h v` (Sec. 7.1), with the elastic and the external
//! forces ([`crate::forces`]). A step takes it `k` times with `h = dt/k` (`rod::substeps`);
//! stiffer strands take the linearly implicit step instead (`rod::implicit`).

use crate::context::StepContext;
use crate::forces::{acceleration, drag};
use crate::math::{Real, Vec3};
use crate::strand::Strand;

/// Where the substeps so far moved a strand's nodes: positions are the step's start plus a
/// displacement summed over the substeps. Adding `v·h` to a position of ~0.1 m rounds at
/// ~4e-9 m, and k roundings per step would add up (a strand at rest drifted 2.4e-6 m in 10 s
/// with k = 4 against 0.6e-6 m with k = 1).
#[derive(Clone, Debug)]
pub struct Motion<const N: usize> {
    /// The positions the displacement is counted from.
    pub start: [Vec3; N],
    /// `Σ v h` over the substeps since `start`.
    pub displacement: [Vec3; N],
}

impl<const N: usize> Motion<N> {
    /// No motion yet: from the strand's positions now.
    #[must_use]
    pub fn from(strand: &Strand<N>) -> Self {
        Motion {
            start: strand.state.position,
            displacement: [Vec3::ZERO; N],
        }
    }

    /// Counts again from the strand's positions now (after something else moved them).
    pub fn restart(&mut self, strand: &Strand<N>) {
        self.start = strand.state.position;
        self.displacement = [Vec3::ZERO; N];
    }
}

/// Symplectic Euler over `h` with the elastic forces `forces` and the external forces
/// `F = M g − ν ẋ` plus the caller's accelerations: `v ← v + h F/m`, then `x ← x + h v`
/// (Kmoch 2009 Sec. 7, Alg. 1 line 4), with `x = x_start + Σ v h` over the substeps so far
/// ([`Motion`]). Nodes 0 and 1 belong to the head.
pub fn symplectic_euler<const N: usize>(
    strand: &mut Strand<N>,
    ctx: &StepContext,
    forces: &[Vec3; N],
    h: Real,
    accelerations: Option<&[Vec3]>,
    motion: &mut Motion<N>,
) {
    let n = strand.rest.nodes.min(N);
    let drag = drag(ctx);
    let (state, inverse_mass) = (&mut strand.state, &strand.rest.inverse_mass);
    let Motion {
        start,
        displacement,
    } = motion;
    // Indexed, not a zipped iterator: `skip(2)` on the zip was left as a call to `nth` on
    // x86-64, a fixed cost per call that a step with few effects on felt.
    for i in 2..n {
        let a = acceleration(
            ctx,
            forces[i],
            state.velocity[i],
            drag,
            inverse_mass[i],
            accelerations,
            i,
        );
        let v = state.velocity[i] + a * h;
        state.velocity[i] = v;
        displacement[i] += v * h;
        state.position[i] = start[i] + displacement[i];
    }
}
