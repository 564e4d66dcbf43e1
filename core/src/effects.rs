//! The set of effects a scene turns on. A stage whose effect is off is never computed.
//!
//! The names are the same everywhere — scene files, the command line, JSON and code:
//! `gravity`, `drag`, `bending`, `twist`, `inextensibility`, `collisions`, `shape`, `wind`,
//! `grabs`, `hair-hair`. Which of them a [`Solver`] can simulate is decided here too.

/// One effect a scene may turn on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Effect {
    /// Uniform gravity `M g`.
    Gravity = 0,
    /// Air drag `−ν ẋ` per node.
    Drag = 1,
    /// Bending elasticity (Kirchhoff rod only).
    Bending = 2,
    /// Twisting elasticity (Kirchhoff rod only).
    Twist = 3,
    /// Segments keep their rest length.
    Inextensibility = 4,
    /// Nodes are kept outside the colliders.
    Collisions = 5,
    /// Global and local shape preservation (DFTL only).
    Shape = 6,
    /// Wind as an external acceleration.
    Wind = 7,
    /// Nodes pinned to moving targets (user interaction).
    Grabs = 8,
    /// Hair–hair interaction as SPH (computed by the std harness, fed back as accelerations).
    HairHair = 9,
}

impl Effect {
    /// Every effect, in the order of their bits.
    pub const ALL: [Effect; 10] = [
        Effect::Gravity,
        Effect::Drag,
        Effect::Bending,
        Effect::Twist,
        Effect::Inextensibility,
        Effect::Collisions,
        Effect::Shape,
        Effect::Wind,
        Effect::Grabs,
        Effect::HairHair,
    ];

    /// The effect's name in scene files, on the command line and in JSON.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Effect::Gravity => "gravity",
            Effect::Drag => "drag",
            Effect::Bending => "bending",
            Effect::Twist => "twist",
            Effect::Inextensibility => "inextensibility",
            Effect::Collisions => "collisions",
            Effect::Shape => "shape",
            Effect::Wind => "wind",
            Effect::Grabs => "grabs",
            Effect::HairHair => "hair-hair",
        }
    }

    /// The effect with this name, if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    const fn bit(self) -> u16 {
        1 << (self as u8)
    }
}

/// A set of [`Effect`]s, as bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Effects(u16);

impl Effects {
    /// No effect at all: the strands drift with their velocities, roots follow the head.
    pub const NONE: Effects = Effects(0);

    /// This set plus `effect`.
    #[must_use]
    pub const fn with(self, effect: Effect) -> Effects {
        Effects(self.0 | effect.bit())
    }

    /// This set without `effect`.
    #[must_use]
    pub const fn without(self, effect: Effect) -> Effects {
        Effects(self.0 & !effect.bit())
    }

    /// Whether `effect` is on.
    #[must_use]
    pub const fn contains(self, effect: Effect) -> bool {
        self.0 & effect.bit() != 0
    }

    /// The set built from a list of effects.
    #[must_use]
    pub const fn from_slice(effects: &[Effect]) -> Effects {
        let mut set = Effects::NONE;
        let mut i = 0;
        while i < effects.len() {
            set = set.with(effects[i]);
            i += 1;
        }
        set
    }

    /// The raw bits (bit `k` is `Effect::ALL[k]`).
    #[must_use]
    pub const fn bits(self) -> u16 {
        self.0
    }

    /// The effects in this set, in bit order.
    pub fn iter(self) -> impl Iterator<Item = Effect> {
        Effect::ALL.into_iter().filter(move |e| self.contains(*e))
    }

    /// The first effect in this set that `solver` cannot simulate, if any.
    #[must_use]
    pub fn unsupported_by(self, solver: Solver) -> Option<Effect> {
        self.iter().find(|e| !solver.supports(*e))
    }
}

/// Which model steps the strands.
///
/// One byte, the variant's index (`repr(u8)`): a world's raw bytes can be checked before they
/// are read as one (`crate::world::WorldLayout`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Solver {
    /// Discrete Kirchhoff rods with fast manifold projection (Kmoch et al. 2009).
    Rod,
    /// Dynamic Follow-The-Leader with shape preservation (Sánchez-Banderas et al. 2015).
    Dftl,
}

impl Solver {
    /// The solver's name in scene files and reports (`"rod"`, `"dftl"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Solver::Rod => "rod",
            Solver::Dftl => "dftl",
        }
    }

    /// Whether this build has the solver: its cargo feature (`rod`, `dftl`; both by default) is
    /// on.
    #[must_use]
    pub const fn is_built(self) -> bool {
        match self {
            Solver::Rod => cfg!(feature = "rod"),
            Solver::Dftl => cfg!(feature = "dftl"),
        }
    }

    /// Whether this solver can simulate `effect`: bending and twist need the rod's energies,
    /// shape preservation is DFTL's.
    #[must_use]
    pub const fn supports(self, effect: Effect) -> bool {
        match self {
            Solver::Rod => !matches!(effect, Effect::Shape),
            Solver::Dftl => !matches!(effect, Effect::Bending | Effect::Twist),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_are_distinct() {
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()), Some(e));
        }
        assert_eq!(Effect::from_name("hairhair"), None);
        let all = Effects::from_slice(&Effect::ALL);
        assert_eq!(all.iter().count(), 10);
        assert!(!all.without(Effect::Wind).contains(Effect::Wind));
    }

    #[test]
    fn solvers_refuse_what_they_cannot_do() {
        let rod = Effects::from_slice(&[Effect::Gravity, Effect::Bending, Effect::Shape]);
        assert_eq!(rod.unsupported_by(Solver::Rod), Some(Effect::Shape));
        assert_eq!(rod.unsupported_by(Solver::Dftl), Some(Effect::Bending));
    }
}
