//! Builds the browser viewer's simulation (`std-harness/viewer`, crate `hairsim-viewer`) for
//! `wasm32-unknown-unknown` so that `hairsim view` can embed the module it serves.
//!
//! The module is built twice, without and with `simd128`, each by a second cargo in its own
//! target folder, `target/viewer-wasm` and `target/viewer-wasm-simd` (or under
//! `$CARGO_TARGET_DIR`, where `.ci/run` checks them): a cargo inside a build script
//! that shared the outer build's folder would wait forever on the outer build's lock. The
//! module is rebuilt from source whenever the core, the file readers or the viewer change, so
//! it never goes stale.
//! Without the wasm target the harness still builds; `hairsim view` then says how to get it.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

const TARGET: &str = "wasm32-unknown-unknown";

/// The two builds of the module: without SIMD, for every browser, and with WebAssembly's
/// 128-bit SIMD (`simd128`, never relaxed SIMD: its results may differ between machines), which
/// the page loads where the browser validates it. Same bits: `simd128`'s lane arithmetic is
/// IEEE single precision, as the scalar instructions are, and the compiler keeps the
/// program's order of operations.
const MODULES: [(&str, &str, &str); 2] = [
    ("hairsim_viewer.wasm", "viewer-wasm", ""),
    (
        "hairsim_viewer_simd.wasm",
        "viewer-wasm-simd",
        "-Ctarget-feature=+simd128",
    ),
];

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = manifest
        .parent()
        .expect("std-harness sits in the workspace")
        .to_path_buf();
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    for watched in [
        "core",
        "std-harness/files",
        "std-harness/viewer",
        "Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={}", root.join(watched).display());
    }
    if !target_installed() {
        println!(
            "cargo:warning=the {TARGET} target is not installed: `hairsim view` will serve no \
             simulation; run `rustup target add {TARGET}` and build again"
        );
        for (module, _, _) in MODULES {
            std::fs::write(out_dir.join(module), b"").expect("OUT_DIR is writable");
        }
        return;
    }
    for (module, folder, flags) in MODULES {
        let built = build_module(&root, folder, flags);
        let out = out_dir.join(module);
        std::fs::copy(&built, &out).unwrap_or_else(|e| panic!("{}: {e}", built.display()));
    }
}

/// Builds the module into `folder` of the target folder with `rustflags`; returns its path.
fn build_module(root: &Path, folder: &str, rustflags: &str) -> PathBuf {
    // The outer build's target folder when the environment names one, as `.ci/run` does.
    let target_dir = env::var_os("CARGO_TARGET_DIR")
        .map_or_else(|| root.join("target"), |dir| root.join(dir))
        .join(folder);
    let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut command = Command::new(cargo);
    command
        .current_dir(root)
        .args(["build", "-q", "-p", "hairsim-viewer", "--target", TARGET])
        .args(["--profile", "viewer", "--target-dir"])
        .arg(&target_dir);
    clear_outer_build(&mut command);
    command.env("CARGO_ENCODED_RUSTFLAGS", rustflags);
    let status = command.status().expect("cargo runs");
    assert!(
        status.success(),
        "building hairsim-viewer for {TARGET} ({folder}) failed (see above)"
    );
    target_dir
        .join(TARGET)
        .join("viewer")
        .join("hairsim_viewer.wasm")
}

/// Whether rustup (or the toolchain) has the standard library for [`TARGET`].
fn target_installed() -> bool {
    let rustc = env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    Command::new(rustc)
        .args(["--print", "target-libdir", "--target", TARGET])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .is_some_and(|dir| Path::new(&dir).is_dir())
}

/// Removes what the outer build set for its own target and tools: its flags (meant for the
/// host, e.g. `-C target-cpu=native`), its target folder, clippy's wrapper and its jobserver.
fn clear_outer_build(command: &mut Command) {
    let keep = [
        "CARGO_HOME",
        "CARGO_NET_",
        "CARGO_HTTP_",
        "CARGO_REGISTRIES_",
        "CARGO_TERM_",
    ];
    for (name, _) in env::vars_os() {
        let name = name.to_string_lossy();
        let outer_cargo = name.starts_with("CARGO_") && !keep.iter().any(|k| name.starts_with(k));
        let outer_tool = matches!(
            name.as_ref(),
            "RUSTFLAGS" | "RUSTDOCFLAGS" | "RUSTC_WORKSPACE_WRAPPER" | "MAKEFLAGS" | "MFLAGS"
        );
        if outer_cargo || outer_tool {
            command.env_remove(name.as_ref());
        }
    }
}
