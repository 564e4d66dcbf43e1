//! Table 3's projection (the `rod_projection` bench's scene and captured states,
//! `hairsim_benches::table3`) run once over the 16 captured steps, for counting instructions with
//! callgrind — load-independent, unlike criterion on a shared machine. Only `measured` is
//! counted:
//!
//! ```text
//! cargo build --release -p hairsim-benches --example projection_instructions
//! valgrind --tool=callgrind --toggle-collect='*measured*' \
//!     target/release/examples/projection_instructions 50 converge collisions
//! ```
//!
//! Arguments: strands (1 or 50), `converge` or `fixed`, `collisions` or `none`. Prints the
//! iterations, contacts and residual; divide callgrind's total by strands × 16 for the
//! instructions per strand-step.

use hairsim_benches::table3::{context, params, predicted_states, project_all, NODES};
use hairsim_core::context::StepContext;
use hairsim_core::{Effect, Mode, StepReport, Strand};

#[inline(never)]
fn measured(strands: &mut [Strand<NODES>], ctx: &StepContext) -> StepReport {
    project_all(strands, ctx)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    assert!(
        args.len() == 4,
        "usage: projection_instructions STRANDS converge|fixed collisions|none"
    );
    let count: usize = args[1].parse().unwrap();
    let mode = if args[2] == "fixed" {
        Mode::FixedCost
    } else {
        Mode::Converge
    };
    let collisions = args[3] == "collisions";
    let states = predicted_states(count);
    let effects: &[Effect] = if collisions {
        &[Effect::Gravity, Effect::Inextensibility, Effect::Collisions]
    } else {
        &[Effect::Gravity, Effect::Inextensibility]
    };
    let p = params(effects, mode);
    let (mut it, mut contacts, mut resid, mut forces) = (0, 0, 0.0f32, 0.0f32);
    for (k, strands) in &states {
        let ctx = context(&p, *k);
        let mut st = strands.clone();
        let r = measured(&mut st, &ctx);
        it += r.iterations_total;
        contacts += r.contacts;
        resid = resid.max(r.residual);
        forces += r.collider_forces[0].length();
    }
    println!("{count} {:?} {collisions}: iterations/strand-step {:.3} contacts/step {:.1} max residual {resid:.2e} mean collider force {:.4} N", mode, it as f64 / (count * states.len()) as f64, contacts as f64 / states.len() as f64, forces / states.len() as f32);
}
