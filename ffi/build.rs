//! Reads the world's capacities from `HAIRSIM_STRANDS` and `HAIRSIM_NODES` (default 4 × 16)
//! and writes them to `$OUT_DIR/capacity.rs`, which `src/lib.rs` includes.
use std::{env, fs, path::PathBuf};

fn capacity(name: &str, default: usize, min: usize, max: usize) -> usize {
    println!("cargo:rerun-if-env-changed={name}");
    let value = match env::var(name) {
        Ok(text) => text
            .trim()
            .parse::<usize>()
            .unwrap_or_else(|_| panic!("{name}={text:?} is not a whole number")),
        Err(_) => default,
    };
    assert!(
        (min..=max).contains(&value),
        "{name}={value} is out of range: {min} to {max}"
    );
    value
}

fn main() {
    // At least 3 nodes: two held by the head and one free (the core refuses fewer).
    let strands = capacity("HAIRSIM_STRANDS", 4, 1, 4096);
    let nodes = capacity("HAIRSIM_NODES", 16, 3, 4096);
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(
        out.join("capacity.rs"),
        format!(
            "/// Strand capacity of the world (`HAIRSIM_STRANDS` at build time).\n\
             pub const STRANDS: usize = {strands};\n\
             /// Node capacity per strand (`HAIRSIM_NODES` at build time).\n\
             pub const NODES: usize = {nodes};\n"
        ),
    )
    .expect("capacity.rs is written to OUT_DIR");
    println!("cargo:rerun-if-changed=build.rs");
}
