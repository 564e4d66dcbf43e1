//! Kmoch 2009 Algorithm 1 line 4, "integrate equations of motion", explicitly: symplectic
//! Euler `v ← v + h F/m`, then `x ← x + h v` (Sec. 7.1), with the elastic and the external
//! forces ([`crate::forces`]). A step takes it `k` times with `h = dt/k` (`rod::substeps`);
//! stiffer strands take the linearly implicit step instead (`rod::implicit`). Written over a
//! [`Kernel`]: one strand, or `W` strands in lanes (`lane::Lanes`), the same operations.

use crate::forces::External;
use crate::math::Vec3;
use crate::precision::{Arithmetic, Kernel, Vector};
use crate::strand::Strand;

/// Where the substeps so far moved a strand's nodes: positions are the step's start plus a
/// displacement summed over the substeps. Adding `v·h` to a position of ~0.1 m rounds at
/// ~4e-9 m, and k roundings per step would add up (a strand at rest drifted 2.4e-6 m in 10 s
/// with k = 4 against 0.6e-6 m with k = 1).
#[derive(Clone, Debug)]
pub struct Motion<const N: usize, V = Vec3> {
    /// The positions the displacement is counted from.
    pub start: [V; N],
    /// `Σ v h` over the substeps since `start`.
    pub displacement: [V; N],
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

    /// Counts again from the strand's positions now (after something else moved them), in
    /// place (a new `Motion` moved in was a copy through the stack).
    pub fn restart(&mut self, strand: &Strand<N>) {
        self.start = strand.state.position;
        self.displacement = [Vec3::ZERO; N];
    }
}

/// No motion yet from `start`, in the vectors of the kernel `P` (lanes of strands).
#[must_use]
pub fn starting_at<P: Kernel, const N: usize>(start: [P::V; N]) -> Motion<N, P::V> {
    Motion {
        start,
        displacement: [<P::V as Vector<P::R>>::ZERO; N],
    }
}

/// The nodes symplectic Euler moves: one strand's, or `W` strands' in lanes.
pub struct Nodes<'a, P: Kernel, const N: usize> {
    /// Nodes in use (nodes 0 and 1 belong to the head and are not moved).
    pub count: usize,
    /// `x`.
    pub position: &'a mut [P::V; N],
    /// `v`.
    pub velocity: &'a mut [P::V; N],
    /// `1/m`.
    pub inverse_mass: &'a [P::R; N],
}

/// Symplectic Euler over `h` with the elastic forces `forces` and the external forces
/// `F = M g − ν ẋ` plus the caller's accelerations: `v ← v + h F/m`, then `x ← x + h v`
/// (Kmoch 2009 Sec. 7, Alg. 1 line 4), with `x = x_start + Σ v h` over the substeps so far
/// ([`Motion`]). Nodes 0 and 1 belong to the head. Lanes outside `active` keep their velocities
/// and displacements (a strand in a block that has taken all its substeps): `true` for one
/// strand.
pub fn symplectic_euler<P: Kernel, const N: usize>(
    nodes: Nodes<'_, P, N>,
    external: &External<P>,
    forces: &[P::V; N],
    h: P::R,
    accelerations: Option<&[P::V]>,
    motion: &mut Motion<N, P::V>,
    active: <P::R as Arithmetic>::Mask,
) {
    let n = nodes.count.min(N);
    let Motion {
        start,
        displacement,
    } = motion;
    // Indexed, not a zipped iterator: `skip(2)` on the zip was left as a call to `nth` on
    // x86-64, a fixed cost per call that a step with few effects on felt.
    if <P::R as Arithmetic>::all(active) {
        // Every lane moves (one strand; a block but in its last substeps): no selects, which
        // SSE2 spends three instructions a component on. A loop of its own: as a branch in
        // the one loop below, the blocks executed 0.5 % more instructions.
        for i in 2..n {
            let velocity = nodes.velocity[i];
            let a =
                external.acceleration(forces[i], velocity, nodes.inverse_mass[i], accelerations, i);
            let v = velocity + a * h;
            nodes.velocity[i] = v;
            displacement[i] += v * h;
            nodes.position[i] = start[i] + displacement[i];
        }
        return;
    }
    for i in 2..n {
        let velocity = nodes.velocity[i];
        let a = external.acceleration(forces[i], velocity, nodes.inverse_mass[i], accelerations, i);
        let v = velocity + a * h;
        let moved = displacement[i] + v * h;
        nodes.velocity[i] = P::V::select(active, v, velocity);
        displacement[i] = P::V::select(active, moved, displacement[i]);
        nodes.position[i] = start[i] + displacement[i];
    }
}
