//! `hairsim check SCENE`.

use anyhow::Result;

use crate::run::{capacity_for, load, HairFileOptions};

/// Checks a scene; one line about it when it is valid.
pub fn check(spec: &str, hair: &HairFileOptions) -> Result<String> {
    let loaded = load(spec, hair)?;
    let p = &loaded.prepared;
    let capacity = capacity_for(p.max_nodes())?;
    Ok(format!(
        "{}: ok: scene \"{}\", {} solver, {} steps of {} s, {} strands ({} nodes, capacity {}), {} followers, {} colliders, {} grabs",
        loaded.source,
        p.name,
        p.params.solver.name(),
        p.steps,
        p.params.dt,
        p.strands.len(),
        p.nodes(),
        capacity,
        p.followers.len(),
        p.colliders.len(),
        p.grabs.len()
    ))
}
