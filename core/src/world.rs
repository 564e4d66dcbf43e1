//! The world: the fixed-capacity convenience around the step pipeline
//! ([`crate::pipeline`]) that firmware keeps in a `static`. The std harness runs the same
//! pipeline on strand blocks of its own `Vec`.

use core::marker::PhantomData;

use crate::capacities::{MAX_COLLIDERS, MAX_GRABS};
use crate::collide::Collider;
use crate::effects::Effect;
use crate::error::{CapacityError, Error, ParamError};
use crate::grab::{retarget, Grab, GrabStatus};
use crate::head::Pose;
use crate::math::{DefaultMath, Math, Vec3};
use crate::params::{DftlCoefficients, Params};
use crate::pipeline::{begin, finish, step_strands_with, Inputs, StepScratch, Stepping};
use crate::report::StepReport;
use crate::strand::{Material, Strand};

/// What the caller hands in each tick.
#[derive(Clone, Copy, Debug)]
pub struct StepInput<'a> {
    /// The head's pose at the end of this step.
    pub head: Pose,
    /// Optional per-node accelerations (SPH, wind from outside), m/s²: node `i` of strand `s`
    /// at `s * N + i`. Shorter slices leave the remaining strands without.
    pub accelerations: Option<&'a [Vec3]>,
}

/// A world's strands: up to `S` of up to `N` nodes.
pub type Strands<const S: usize, const N: usize> = heapless::Vec<Strand<N>, S>;
/// A world's colliders.
pub type Colliders = heapless::Vec<Collider, MAX_COLLIDERS>;
/// A world's grabs.
pub type Grabs = heapless::Vec<Grab, MAX_GRABS>;

/// A fixed-capacity world: up to `S` strands of up to `N` nodes, stepped with the math
/// backend `M`. Holds no heap memory; `World::new` is `const`, so a world can live in a
/// `static`.
#[derive(Clone, Debug)]
pub struct World<const S: usize, const N: usize, M: Math = DefaultMath> {
    params: Params,
    /// DFTL's coefficients at `params.dt`, computed once in `configure` (never per step).
    dftl: DftlCoefficients,
    strands: Strands<S, N>,
    colliders: Colliders,
    grabs: Grabs,
    head: Pose,
    steps: u64,
    /// A grab target given since the last step was not finite (and was ignored): the next
    /// step's report flags it.
    bad_target: bool,
    /// The solver's scratch space: built by `configure` (or by the first step of a world
    /// never configured), made anew when `configure` changes the solver, never per step (not
    /// state: not hashed, snapshotted or cloned).
    scratch: StepScratch<M, N>,
    math: PhantomData<M>,
}

/// Where a world keeps the bytes that not every value fits, as offsets from the world's
/// start: for a caller that checks a world's raw bytes before it reads them as a `World` (the
/// C ABI's `hairsim_check`, after a reset in the middle of a call or a stray write). The
/// enums are one byte, the variant's index (`repr(u8)`): [`Solver`](crate::Solver) and
/// [`crate::params::Mode`] and [`crate::params::TwistMethod`] below 2; the world's flag of a
/// bad grab target since the last step is a `bool`; the solver's scratch space's variant
/// ([`StepScratch`]) is a `u32` word below 2. The lists are
/// `heapless::Vec`s ([`Strands`], [`Colliders`], [`Grabs`]): every byte pattern is one, but
/// their lengths must be at most their capacities before their elements are read. Within
/// an element, the public fields' offsets are `core::mem::offset_of!`'s: a strand's
/// `rest.nodes` (3 to `N`) and `schedule.implicit_bending` (a `bool`), a collider's `shape` (its
/// first byte, the variant, below 3: [`Shape`](crate::Shape) is `repr(C, u8)`) and
/// `attached_to_head` (a `bool`), a grab's `status` (below 3), `strand`, `node` and `coupling`
/// (an `Option<Coupling>`, whose tag Rust places without a promise: the C ABI's tests check
/// where). Everything else in a world is floats and integers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorldLayout {
    /// `params.solver`.
    pub solver: usize,
    /// `params.mode`.
    pub mode: usize,
    /// `params.rod.twist`.
    pub twist: usize,
    /// The flag of a non-finite grab target given since the last step (a `bool`).
    pub bad_target: usize,
    /// The strands, a [`Strands`].
    pub strands: usize,
    /// The colliders, a [`Colliders`].
    pub colliders: usize,
    /// The grabs, a [`Grabs`].
    pub grabs: usize,
    /// The solver's scratch space, whose first word (a `u32`) is its variant, below 3
    /// ([`StepScratch`](crate::pipeline::StepScratch)).
    pub scratch: usize,
}

impl<const S: usize, const N: usize, M: Math> World<S, N, M> {
    /// Where this world type keeps what [`WorldLayout`] lists.
    pub const LAYOUT: WorldLayout = WorldLayout {
        solver: core::mem::offset_of!(Self, params.solver),
        mode: core::mem::offset_of!(Self, params.mode),
        twist: core::mem::offset_of!(Self, params.rod.twist),
        bad_target: core::mem::offset_of!(Self, bad_target),
        strands: core::mem::offset_of!(Self, strands),
        colliders: core::mem::offset_of!(Self, colliders),
        grabs: core::mem::offset_of!(Self, grabs),
        scratch: core::mem::offset_of!(Self, scratch),
    };
}

impl<const S: usize, const N: usize, M: Math> Default for World<S, N, M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const S: usize, const N: usize, M: Math> World<S, N, M> {
    /// An empty world with [`Params::DEFAULT`] (the rod's preset; DFTL's in a build without the
    /// rod): usable to initialise a `static`.
    #[must_use]
    #[inline(always)]
    pub const fn new() -> Self {
        World {
            params: Params::DEFAULT,
            dftl: DftlCoefficients::NONE,
            strands: heapless::Vec::new(),
            colliders: heapless::Vec::new(),
            grabs: heapless::Vec::new(),
            head: Pose::IDENTITY,
            steps: 0,
            bad_target: false,
            scratch: StepScratch::new(),
            math: PhantomData,
        }
    }

    /// An empty world with `params`, after checking them.
    pub fn with_params(params: Params) -> Result<Self, ParamError> {
        let mut world = Self::new();
        world.configure(params)?;
        Ok(world)
    }

    /// Replaces the parameters (time step included) after checking them.
    pub fn configure(&mut self, params: Params) -> Result<(), ParamError> {
        params.validate()?;
        self.scratch.suit(params.solver);
        self.params = params;
        self.dftl = params.dftl.at_step(params.dt);
        Ok(())
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Adds a strand; returns its index. A full world returns an error and is unchanged.
    pub fn add_strand(&mut self, strand: Strand<N>) -> Result<usize, CapacityError> {
        self.strands
            .push(strand)
            .map_err(|_| CapacityError::Strands { capacity: S })?;
        Ok(self.strands.len() - 1)
    }

    /// Adds a strand at rest along `points` of `material` ([`Strand::from_polyline`]), built
    /// in the world's own storage rather than on the stack and moved in (a strand is `120 N`
    /// bytes, and firmware stacks are small); returns its index. A refused strand or a full
    /// world leaves the world unchanged.
    pub fn add_strand_from_polyline(
        &mut self,
        points: &[Vec3],
        material: &Material,
    ) -> Result<usize, Error> {
        let index = self.strands.len();
        if index == S {
            return Err(CapacityError::Strands { capacity: S }.into());
        }
        // The push cannot fail (checked above), and an empty strand is written in place.
        let _ = self.strands.push(Strand::EMPTY);
        if let Err(e) = self.strands[index].rebuild(points, material) {
            self.strands.truncate(index);
            return Err(e.into());
        }
        Ok(index)
    }

    /// `Ok` if `effect` is on, else the error saying that `item` needs it.
    fn needs(&self, effect: Effect, item: &'static str) -> Result<(), Error> {
        if self.params.effects.contains(effect) {
            Ok(())
        } else {
            Err(ParamError::EffectOff {
                effect: effect.name(),
                item,
            }
            .into())
        }
    }

    /// Adds a collider; returns its index. Refused while the `collisions` effect is off: a
    /// collider would do nothing. (Turning `collisions` off later keeps the colliders, and each
    /// step reports them inactive, [`crate::report::Flags::COLLIDERS_INACTIVE`].)
    pub fn add_collider(&mut self, collider: Collider) -> Result<usize, Error> {
        self.needs(Effect::Collisions, "a collider")?;
        collider.shape.check()?;
        self.colliders
            .push(collider)
            .map_err(|_| CapacityError::Colliders {
                capacity: MAX_COLLIDERS,
            })?;
        Ok(self.colliders.len() - 1)
    }

    /// Adds a grab; returns its index. Refused while the `grabs` effect is off, as
    /// [`World::add_collider`] (a step reports grabs held with `grabs` off,
    /// [`crate::report::Flags::GRABS_INACTIVE`]).
    pub fn add_grab(&mut self, grab: Grab) -> Result<usize, Error> {
        self.needs(Effect::Grabs, "a grab")?;
        let refuse = |field, allowed| Err(ParamError::OutOfRange { field, allowed }.into());
        let Some(strand) = self.strands.get(grab.strand as usize) else {
            return refuse("grab.strand", "the index of a strand the world holds");
        };
        if grab.node < 2 || grab.node as usize >= strand.nodes() {
            return refuse(
                "grab.node",
                "2 (nodes 0 and 1 follow the head) to the strand's last",
            );
        }
        if !crate::math::is_finite(grab.target) {
            return refuse("grab.target", "finite coordinates, m");
        }
        if grab.force_limit.is_nan() || grab.force_limit <= 0.0 {
            return refuse("grab.force_limit", "> 0 N (infinite: it never slips)");
        }
        if let Some(coupling) = grab.coupling {
            coupling.check()?;
        }
        let grab = Grab {
            previous_target: grab.target,
            ..grab
        };
        self.grabs.push(grab).map_err(|_| CapacityError::Grabs {
            capacity: MAX_GRABS,
        })?;
        Ok(self.grabs.len() - 1)
    }

    /// Moves grab `grab`'s target (ignored for an unknown index; a non-finite target is
    /// ignored, the grab keeps its target, and the next step's report flags
    /// [`crate::Flags::BAD_INPUT`]).
    pub fn set_grab_target(&mut self, grab: usize, target: Vec3) {
        if let Some(g) = self.grabs.get_mut(grab) {
            self.bad_target |= !retarget(g, target);
        }
    }

    /// Releases grab `grab`.
    pub fn release_grab(&mut self, grab: usize) {
        if let Some(g) = self.grabs.get_mut(grab) {
            g.status = GrabStatus::Released;
        }
    }

    /// The strands.
    #[must_use]
    pub fn strands(&self) -> &[Strand<N>] {
        &self.strands
    }

    /// The strands, mutable (to set an initial state).
    pub fn strands_mut(&mut self) -> &mut [Strand<N>] {
        &mut self.strands
    }

    /// The colliders.
    #[must_use]
    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    /// The grabs.
    #[must_use]
    pub fn grabs(&self) -> &[Grab] {
        &self.grabs
    }

    /// The head's current pose.
    #[must_use]
    pub fn head(&self) -> Pose {
        self.head
    }

    /// Steps taken so far.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The state hash of every strand ([`crate::hash`] documents the order).
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        crate::hash::state_hash(&self.strands)
    }

    /// Advances the world by one `dt`. Never panics and never fails: what went wrong is in the
    /// report (a non-finite head pose is ignored and flagged; a strand that diverges is rolled
    /// back and named).
    pub fn step(&mut self, input: &StepInput<'_>) -> StepReport {
        let mut report = StepReport::default();
        self.step_into(input, &mut report);
        report
    }

    /// [`Self::step`], its report written over `report`: what a loop that keeps one report
    /// calls (the report is not copied out: on the Cortex-M4F, the copy was 0.4 % of a
    /// DFTL step of 8 × 16 nodes).
    pub fn step_into(&mut self, input: &StepInput<'_>, report: &mut StepReport) {
        report.clear();
        if core::mem::take(&mut self.bad_target) {
            report.flags.insert(crate::report::Flags::BAD_INPUT);
        }
        let world = Stepping {
            params: &self.params,
            dftl: self.dftl,
            colliders: &self.colliders,
            grabs: &mut self.grabs,
            strands: &self.strands,
            head: self.head,
            steps: self.steps,
        };
        let inputs = Inputs {
            head: input.head,
            grab_targets: &[],
            released: &[],
        };
        let ctx = begin(world, &inputs, report);
        let accelerations = input.accelerations;
        self.scratch.suit(self.params.solver);
        let scratch = Some(&mut self.scratch);
        let at = (0, &self.grabs[..]);
        step_strands_with::<M, N>(&ctx, &mut self.strands, at, accelerations, scratch, report);
        finish(&mut self.grabs, report);
        self.head = ctx.head;
        self.steps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::{Effect, Effects};
    use crate::math::{Libm, Real};
    use crate::report::Flags;
    use crate::strand::Material;

    fn world() -> World<2, 8, Libm> {
        let mut w = World::with_params(Params {
            effects: Effects::NONE.with(Effect::Gravity),
            ..Params::DEFAULT
        })
        .unwrap();
        let points: [Vec3; 6] = core::array::from_fn(|i| Vec3::new(0.01 * i as Real, 0.0, 0.0));
        w.add_strand(Strand::from_polyline(&points, &Material::HUMAN_HAIR).unwrap())
            .unwrap();
        w
    }

    #[test]
    fn free_nodes_fall_held_roots_stay() {
        let mut w = world();
        let input = StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        };
        for _ in 0..100 {
            w.step(&input);
        }
        let s = &w.strands()[0];
        assert_eq!(s.state.position[0], Vec3::ZERO);
        assert_eq!(s.state.position[1], Vec3::new(0.01, 0.0, 0.0));
        // Symplectic Euler: y_k = −g h² k(k+1)/2 after k steps.
        let expected = -9.81 * 1e-6 * 100.0 * 101.0 / 2.0;
        assert!(
            (s.state.position[5].y - expected).abs() < 1e-5,
            "{}",
            s.state.position[5].y
        );
    }

    #[test]
    fn a_collider_or_grab_whose_effect_is_off_is_refused_by_name() {
        let mut w = world();
        let sphere = Collider {
            shape: crate::collide::Shape::Sphere {
                centre: Vec3::new(0.0, -1.0, 0.0),
                radius: 0.05,
            },
            attached_to_head: false,
        };
        let grab = Grab::new(0, 3, Vec3::new(0.03, 0.0, 0.0), 1.0);
        let refused = |effect, item| Err(Error::Param(ParamError::EffectOff { effect, item }));
        assert_eq!(w.add_collider(sphere), refused("collisions", "a collider"));
        assert_eq!(w.add_grab(grab), refused("grabs", "a grab"));
        assert_eq!(
            std::string::ToString::to_string(&w.add_collider(sphere).unwrap_err()),
            "a collider needs the effect \"collisions\", which is off: turn it on before adding one"
        );
        let on = w
            .params()
            .effects
            .with(Effect::Collisions)
            .with(Effect::Grabs);
        let params = Params {
            effects: on,
            ..*w.params()
        };
        w.configure(params).unwrap();
        assert_eq!((w.add_collider(sphere), w.add_grab(grab)), (Ok(0), Ok(0)));
        let still = StepInput {
            head: Pose::IDENTITY,
            accelerations: None,
        };
        let inactive = Flags::COLLIDERS_INACTIVE;
        assert!(!w.step(&still).flags.contains(inactive));
        // Switched off on purpose, both stay and the report says they did nothing.
        w.configure(Params {
            effects: on.without(Effect::Collisions).without(Effect::Grabs),
            ..params
        })
        .unwrap();
        let flags = w.step(&still).flags;
        assert!(flags.contains(inactive) && flags.contains(Flags::GRABS_INACTIVE));
    }

    #[test]
    fn full_world_refuses_a_strand_and_keeps_the_rest() {
        let mut w = world();
        let s = w.strands()[0].clone();
        assert_eq!(w.add_strand(s.clone()), Ok(1));
        assert_eq!(w.add_strand(s), Err(CapacityError::Strands { capacity: 2 }));
        assert_eq!(w.strands().len(), 2);
    }

    #[test]
    fn a_non_finite_acceleration_rolls_back_and_is_named() {
        let mut w = world();
        let mut acc = [Vec3::ZERO; 8];
        acc[4] = Vec3::new(Real::NAN, 0.0, 0.0);
        let before = w.state_hash();
        let report = w.step(&StepInput {
            head: Pose::IDENTITY,
            accelerations: Some(&acc),
        });
        assert!(report.flags.contains(Flags::ROLLED_BACK));
        assert_eq!(report.rolled_back_strands.as_slice(), &[0]);
        assert_eq!(w.state_hash(), before);
    }

    #[test]
    fn a_non_finite_head_pose_is_ignored_and_flagged() {
        let mut w = world();
        let mut head = Pose::IDENTITY;
        head.position.x = Real::INFINITY;
        let report = w.step(&StepInput {
            head,
            accelerations: None,
        });
        assert!(report.flags.contains(Flags::BAD_INPUT));
        assert!(w.strands()[0].is_finite());
    }
}
