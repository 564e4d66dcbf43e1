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
    let state = &mut strand.state;
    let Motion {
        start,
        displacement,
    } = motion;
    let nodes = state
        .position
        .iter_mut()
        .zip(start.iter().zip(displacement.iter_mut()))
        .zip(state.velocity.iter_mut())
        .zip(forces.iter().zip(&strand.rest.inverse_mass))
        .enumerate()
        .take(n)
        .skip(2);
    for (i, (((x, (x0, d)), v), (force, inverse_mass))) in nodes {
        let a = acceleration(ctx, *force, *v, drag, *inverse_mass, accelerations, i);
        *v += a * h;
        *d += *v * h;
        *x = *x0 + *d;
    }
}
