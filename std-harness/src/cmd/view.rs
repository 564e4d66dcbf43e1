//! `hairsim view [SCENE|FILE]`.

use std::io::Write;

use anyhow::Result;

use crate::builtin::DEFAULT_SCENE;
use crate::view::{initial, Server};

/// Serves the viewer for SCENE on 127.0.0.1:`port` until the process is stopped. The URL is
/// printed (and flushed) as soon as the server listens, on a line of its own.
///
/// # Errors
/// SCENE fails to load, or the server cannot listen or stops.
pub fn view(scene: Option<&str>, port: u16) -> Result<String> {
    let spec = scene.unwrap_or(DEFAULT_SCENE);
    let server = Server::bind(port, initial(spec)?)?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", server.url())?;
    out.flush()?;
    drop(out);
    eprintln!("hairsim view: serving {spec}; open the address above in a browser, Ctrl-C stops");
    server.serve()?;
    Ok(String::new())
}
