//! The page's calls: plain C exports over one [`Session`] and four buffers this module owns.
//!
//! The page writes its arguments (names, file bytes, scene text) into the input buffer
//! ([`hs_input`] returns its address for a length), calls, and reads text (JSON or an error
//! message) from the output buffer ([`hs_output_ptr`], [`hs_output_len`]) or positions from
//! the position buffers. A call that can fail returns 0 on success and 1 with the error's
//! message in the output buffer. Nothing here panics on the page's input.
//!
//! `#[no_mangle]` is what the `unsafe_code` lint objects to in this module: the exports'
//! names must be the page's. No function dereferences a pointer; the addresses handed out
//! are of `Vec`s owned here, valid until the next call that resizes them.
#![allow(unsafe_code)]

use std::cell::RefCell;

use hairsim_core::{Effect, Solver, Vec3};
use hairsim_files::builtin::BUILTINS;
use serde_json::json;

use crate::session::{Session, Source};

/// What the exports keep between calls.
#[derive(Default)]
struct State {
    session: Option<Session>,
    input: Vec<u8>,
    output: String,
    positions: Vec<f32>,
    offsets: Vec<u32>,
    floats: Vec<f32>,
    bytes: Vec<u8>,
}

thread_local! {
    static STATE: RefCell<State> = RefCell::new(State::default());
}

fn with<R>(f: impl FnOnce(&mut State) -> R) -> R {
    STATE.with(|s| f(&mut s.borrow_mut()))
}

/// 0, or 1 with `message` in the output buffer.
fn answer(state: &mut State, result: Result<(), String>) -> i32 {
    match result {
        Ok(()) => 0,
        Err(message) => {
            state.output = message;
            1
        }
    }
}

/// The input buffer split into consecutive pieces of `lengths` bytes (empty past its end).
fn pieces<const K: usize>(input: &[u8], lengths: [u32; K]) -> [&[u8]; K] {
    let mut out = [&input[..0]; K];
    let mut at = 0usize;
    for (piece, len) in out.iter_mut().zip(lengths) {
        let end = at.saturating_add(len as usize).min(input.len());
        *piece = &input[at.min(end)..end];
        at = end;
    }
    out
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Loads `source`; the session is replaced only on success.
fn load(state: &mut State, source: Result<Source, String>) -> i32 {
    let result = source.and_then(Session::load).map(|s| {
        state.session = Some(s);
    });
    answer(state, result)
}

/// Runs `f` on the session (an error when none is loaded).
fn on_session(f: impl FnOnce(&mut Session) -> Result<(), String>) -> i32 {
    with(|state| {
        let result = match state.session.as_mut() {
            Some(session) => f(session),
            None => Err("no scene loaded".into()),
        };
        answer(state, result)
    })
}

/// Runs `f` on the session and puts the text it gives into the output (an error when none is
/// loaded).
fn output_of(f: impl FnOnce(&mut Session) -> String) -> i32 {
    with(|state| {
        let result = match state.session.as_mut() {
            Some(session) => {
                state.output = f(session);
                Ok(())
            }
            None => Err("no scene loaded".into()),
        };
        answer(state, result)
    })
}

/// The address of an input buffer of `len` bytes for the next call's arguments.
#[no_mangle]
pub extern "C" fn hs_input(len: u32) -> *mut u8 {
    with(|s| {
        s.input.clear();
        s.input.resize(len as usize, 0);
        s.input.as_mut_ptr()
    })
}

/// The address of the output text (UTF-8).
#[no_mangle]
pub extern "C" fn hs_output_ptr() -> *const u8 {
    with(|s| s.output.as_ptr())
}

/// The output text's length in bytes.
#[no_mangle]
pub extern "C" fn hs_output_len() -> u32 {
    with(|s| u32::try_from(s.output.len()).unwrap_or(0))
}

/// The built-in scenes as JSON (`[{name, about}]`) into the output.
#[no_mangle]
pub extern "C" fn hs_builtins() {
    let list: Vec<_> = BUILTINS
        .iter()
        .map(|b| json!({"name": b.name, "about": b.about}))
        .collect();
    with(|s| s.output = json!(list).to_string());
}

/// Loads the built-in scene whose name is the input's first `name_len` bytes.
#[no_mangle]
pub extern "C" fn hs_load_builtin(name_len: u32) -> i32 {
    with(|state| {
        let [name] = pieces(&state.input, [name_len]);
        let source = Source::builtin(&text(name));
        load(state, source)
    })
}

/// Loads a hair file in its default scene: the input holds its name, then its bytes.
#[no_mangle]
pub extern "C" fn hs_load_hair_file(name_len: u32, bytes_len: u32) -> i32 {
    with(|state| {
        let [name, bytes] = pieces(&state.input, [name_len, bytes_len]);
        let source = Source::HairFile {
            name: text(name),
            bytes: bytes.to_vec(),
        };
        load(state, Ok(source))
    })
}

/// Loads a scene file: the input holds its name, its text, then the name and bytes of the
/// hair file it reads (both empty if none).
#[no_mangle]
pub extern "C" fn hs_load_scene_file(
    name_len: u32,
    text_len: u32,
    hair_name_len: u32,
    hair_len: u32,
) -> i32 {
    with(|state| {
        let lengths = [name_len, text_len, hair_name_len, hair_len];
        let [name, scene, hair_name, hair] = pieces(&state.input, lengths);
        let source = Source::SceneFile {
            name: text(name),
            text: text(scene),
            hair: (!hair_name.is_empty()).then(|| (text(hair_name), hair.to_vec())),
        };
        load(state, Ok(source))
    })
}

/// The file name of the hair file the scene file in the input reads (its name, then its
/// text) into the output: empty if it reads none.
#[no_mangle]
pub extern "C" fn hs_scene_hair_file(name_len: u32, text_len: u32) -> i32 {
    with(|state| {
        let [name, scene] = pieces(&state.input, [name_len, text_len]);
        let result = crate::session::scene_hair_file(&text(name), &text(scene)).map(|file| {
            state.output = file.unwrap_or_default();
        });
        answer(state, result)
    })
}

/// Advances the scene by `steps` steps; returns the steps taken since the start (0 with no
/// scene).
#[no_mangle]
pub extern "C" fn hs_step(steps: u32) -> u32 {
    with(|state| match state.session.as_mut() {
        Some(session) => {
            session.step(steps);
            u32::try_from(session.steps()).unwrap_or(u32::MAX)
        }
        None => 0,
    })
}

/// Back to the scene's start.
#[no_mangle]
pub extern "C" fn hs_reset() -> i32 {
    on_session(Session::reset)
}

/// Copies every node's position into the position buffers; returns the number of nodes.
#[no_mangle]
pub extern "C" fn hs_positions() -> u32 {
    with(|state| {
        let State {
            session,
            positions,
            offsets,
            ..
        } = state;
        match session {
            Some(session) => session.positions(positions, offsets),
            None => {
                positions.clear();
                offsets.clear();
            }
        }
        u32::try_from(positions.len() / 3).unwrap_or(0)
    })
}

/// The address of the positions (`x, y, z` per node, strand after strand).
#[no_mangle]
pub extern "C" fn hs_positions_ptr() -> *const f32 {
    with(|s| s.positions.as_ptr())
}

/// The address of each strand's first node index (strands + 1 entries).
#[no_mangle]
pub extern "C" fn hs_offsets_ptr() -> *const u32 {
    with(|s| s.offsets.as_ptr())
}

/// The number of entries at [`hs_offsets_ptr`].
#[no_mangle]
pub extern "C" fn hs_offsets_len() -> u32 {
    with(|s| u32::try_from(s.offsets.len()).unwrap_or(0))
}

/// The followers into the float buffer ([`hs_floats_ptr`]: leader index, then the root
/// offset in the head's frame, four floats each); returns their number.
#[no_mangle]
pub extern "C" fn hs_followers() -> u32 {
    with(|state| {
        match &state.session {
            Some(session) => session.followers(&mut state.floats),
            None => state.floats.clear(),
        }
        u32::try_from(state.floats.len() / 4).unwrap_or(0)
    })
}

/// The address of the float buffer.
#[no_mangle]
pub extern "C" fn hs_floats_ptr() -> *const f32 {
    with(|s| s.floats.as_ptr())
}

/// One byte of flags per strand (`stepper::flag`) into the byte buffer ([`hs_bytes_ptr`]);
/// returns the number of strands.
#[no_mangle]
pub extern "C" fn hs_strand_flags() -> u32 {
    with(|state| {
        match state.session.as_mut() {
            Some(session) => session.strand_flags(&mut state.bytes),
            None => state.bytes.clear(),
        }
        u32::try_from(state.bytes.len()).unwrap_or(0)
    })
}

/// The address of the byte buffer.
#[no_mangle]
pub extern "C" fn hs_bytes_ptr() -> *const u8 {
    with(|s| s.bytes.as_ptr())
}

/// What the steps since the last call reported, as JSON into the output (counting starts
/// anew).
#[no_mangle]
pub extern "C" fn hs_events() -> i32 {
    output_of(|session| session.take_events().to_string())
}

/// The scene as the page has edited it, as a scene file, into the output.
#[no_mangle]
pub extern "C" fn hs_scene_toml() -> i32 {
    output_of(|session| session.scene_toml())
}

/// The session's status as JSON into the output.
#[no_mangle]
pub extern "C" fn hs_status() -> i32 {
    output_of(|session| session.status().to_string())
}

/// Switches to the rod (1) or DFTL (0), restarting the scene.
#[no_mangle]
pub extern "C" fn hs_set_solver(rod: u32) -> i32 {
    let solver = if rod == 1 { Solver::Rod } else { Solver::Dftl };
    on_session(|s| s.set_solver(solver))
}

/// Turns effect number `effect` (`Effect::ALL`'s order) on (1) or off (0).
#[no_mangle]
pub extern "C" fn hs_set_effect(effect: u32, on: u32) -> i32 {
    let Some(&effect) = Effect::ALL.get(effect as usize) else {
        return with(|state| answer(state, Err(format!("no effect number {effect}"))));
    };
    on_session(|s| s.set_effect(effect, on == 1))
}

/// The rod's twist method: Newton (1) or hair-optimised (0).
#[no_mangle]
pub extern "C" fn hs_set_twist(newton: u32) -> i32 {
    let method = if newton == 1 {
        "newton"
    } else {
        "hair-optimised"
    };
    on_session(|s| s.set_twist(method))
}

/// Grabs node `node` of strand `strand` where it is.
#[no_mangle]
pub extern "C" fn hs_grab(strand: u32, node: u32) -> i32 {
    on_session(|s| s.grab(strand as usize, node as usize))
}

/// Moves the hand's target to `(x, y, z)`, m.
#[no_mangle]
pub extern "C" fn hs_move_hand(x: f32, y: f32, z: f32) {
    on_session(|s| {
        s.move_hand(Vec3::new(x, y, z));
        Ok(())
    });
}

/// Lets go of the hand's grab.
#[no_mangle]
pub extern "C" fn hs_release() {
    on_session(|s| {
        s.release();
        Ok(())
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_never_read_past_the_input() {
        let input = b"abcdef";
        assert_eq!(pieces(input, [2, 3, 9]), [&b"ab"[..], b"cde", b"f"]);
        assert_eq!(pieces(input, [u32::MAX, 1]), [&b"abcdef"[..], b""]);
    }
}
