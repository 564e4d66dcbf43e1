//! SB15 Algorithm 1 lines 24–26: velocity update with the DFTL correction, eq. (14) (Müller,
//! Kim, Chentanez 2012, eq. 9), then `x ← x*`.
//!
//! `v_i = (x*_i − x_i)/Δt − s_d C_i/Δt`, where `C_i` is node `i`'s share of the reaction to
//! the corrections of the nodes after it:
//!
//! `C_i = (1 + φ) Δx^lcl_{i+1} + Δx^inex_{i+1} − φ Δx^lcl_{i+2}`, `φ = (1 − s_l)/2`.
//!
//! The follow-the-leader constraint is *between* nodes `i` and `i + 1` but moves node `i + 1`
//! alone; `−s_d Δx^inex_{i+1}` hands node `i` (most of) the equal and opposite share, as in
//! Müller 2012. The local shape constraint (eq. 12) is not between two nodes: it pulls node
//! `i + 2` towards the rest offset carried by node `i + 1`'s frame, whose tangent is the
//! segment `i → i + 1` — a bending constraint on three nodes. Its reaction balances force
//! *and* torque only as the stencil `(1, −2, 1)`: `+Δx` on node `i + 2`, `−2Δx` on `i + 1`,
//! `+Δx` on `i`. SB15's eq. 14 hands back `−Δx` to node `i + 1` alone: the force balances,
//! the torque does not, and the couple left over pumps energy into a zig-zag mode. Where the
//! shape fraction is small (the spring rule gives `s_l` = 0.022 at 1 ms) nothing damps it and
//! a groom crinkles within 50 steps; at 60 Hz (`s_l` = 0.86) the projection's own
//! dissipation hides it (`docs/design-departures.md`, with the measurements). The full
//! stencil (`φ = 1`) is unstable where `s_l` is large (the reaction, fed back one step late,
//! overshoots); `φ = (1 − s_l)/2` keeps half the torque balance where the constraint is a
//! soft spring and fades where the projection is nearly rigid: in a 24-node 2-D chain curved
//! 0.08 rad a segment, the linearised step's spectral radius stays below 1 at every step from
//! 0.5 ms to 60 Hz, where SB15's form exceeds 1 up to 2 ms (1.017 at 1 ms;
//! `docs/study/dftl_chain.py`).
//!
//! SB15's eq. (14) also lists the global correction `Δx^gbl_{i+1}`; it is left out here: the
//! global constraint ties node `i + 1` to the head, not to node `i`, so feeding it back
//! pushes node `i` with no partner (measured: styled strands pushed for 0.2 s then left 3 s
//! stayed 3–7 cm from rest with it, 2.3 cm without).
//!
//! The solver finishes each node two nodes behind, as soon as the corrections of both nodes
//! after it are known ([`Pending`]), so the whole step is still one pass. Without shape the
//! local terms are zero and a node is whole one node behind: the blocks store it then
//! (`pipeline::dftl::hand_on_lanes`).

use super::node::Setup;
use crate::lane::{Lane, V3};

/// Node `i − 2`'s velocity without the term node `i` adds (once node `i − 1` is advanced its
/// position is final and stored, and its velocity pends here).
#[derive(Clone, Copy, Debug)]
pub struct Pending<T: Lane> {
    /// `(x*_{i−2} − x_{i−2})/Δt − s_d ((1 + φ) Δx^lcl_{i−1} + Δx^inex_{i−1})/Δt`.
    pub velocity: V3<T>,
}

impl<T: Lane> Pending<T> {
    /// Before node 2: nothing pending (the held node 1 takes no reaction).
    #[inline(always)]
    #[must_use]
    pub fn start() -> Self {
        Pending {
            velocity: V3::zero(),
        }
    }

    /// Node `i` advanced with its local and follow-the-leader corrections; node `i − 1` went
    /// from `x` at the start of the step to its final `x_star`. Returns node `i − 2`'s
    /// velocity, now complete, and node `i − 1`'s, pending. A node past the strand's end hands
    /// on zeros (`a − 0` changes no bit). Without shape the local terms are not computed
    /// (`0 · φ` cannot be folded away: the compiler must allow for a non-finite `φ`).
    #[inline(always)]
    #[must_use]
    pub fn hand_on(
        &self,
        setup: &Setup,
        x_star: V3<T>,
        x: V3<T>,
        local: V3<T>,
        inextensible: V3<T>,
    ) -> (V3<T>, Self) {
        let moved = (x_star - x).scale(T::splat(setup.inv_dt));
        let feedback = T::splat(setup.damping_over_dt);
        if !setup.shape {
            let next = moved - inextensible.scale(feedback);
            return (self.velocity, Pending { velocity: next });
        }
        let phi = setup.coefficients.bending_reaction;
        let finished = self.velocity + local.scale(T::splat(phi) * feedback);
        let reaction = local.scale(T::splat(1.0 + phi)) + inextensible;
        let next = moved - reaction.scale(feedback);
        (finished, Pending { velocity: next })
    }
}
