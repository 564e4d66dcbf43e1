//! The built-in scenes `hairsim scenes` lists.

/// A built-in scene: its name (as in the papers) and one line about it.
#[derive(Clone, Copy, Debug)]
pub struct Builtin {
    /// Name, as typed on the command line.
    pub name: &'static str,
    /// One line for `hairsim scenes`.
    pub about: &'static str,
}

/// The scene `hairsim run` runs when none is named.
pub const DEFAULT_SCENE: &str = "firmware";

/// Every built-in scene.
pub const BUILTINS: &[Builtin] = &[Builtin {
    name: "firmware",
    about: "the firmware example's scene: 4 rod strands of 12-15 nodes on a 5 cm head shaking at 10 rad/s, 1000 steps at 1 ms (same hash as under QEMU)",
}];

/// The built-in scene called `name`.
#[must_use]
pub fn find(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}
