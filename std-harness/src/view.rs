//! `hairsim view`'s web server. It serves the page (`std-harness/viewer/web`), the viewer's
//! simulation compiled to WebAssembly (built by `build.rs`) and the scene it was asked to
//! open, all from memory; it runs no simulation and answers nothing but these files. The
//! simulation runs in the page, on the core compiled to `wasm32-unknown-unknown`.

use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use serde_json::json;

use hairsim_viewer::session::Source;

use crate::run::{load, HairFileOptions};
use crate::scene::{prepare::hair_file_path, HairSpec};

/// The viewer's simulation (`hairsim-viewer` for `wasm32-unknown-unknown`); empty when the
/// harness was built without that target.
pub const WASM: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/hairsim_viewer.wasm"));

/// The same built with WebAssembly's 128-bit SIMD (`simd128`), which the page loads where the
/// browser has it: the same bits, faster.
pub const WASM_SIMD: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/hairsim_viewer_simd.wasm"));

/// A file of the page: where it is served and what it holds.
struct Asset {
    path: &'static str,
    content_type: &'static str,
    bytes: &'static [u8],
}

const HTML: &str = "text/html; charset=utf-8";
const SCRIPT: &str = "text/javascript; charset=utf-8";

/// One of the page's files in `std-harness/viewer/web`, served at `/NAME`.
macro_rules! page_file {
    ($name:literal, $content_type:expr) => {
        Asset {
            path: concat!("/", $name),
            content_type: $content_type,
            bytes: include_bytes!(concat!("../viewer/web/", $name)),
        }
    };
}

/// The page's files, embedded in the binary.
const ASSETS: &[Asset] = &[
    page_file!("index.html", HTML),
    page_file!("viewer.js", SCRIPT),
    page_file!("simulation.js", SCRIPT),
    page_file!("clock.js", SCRIPT),
    page_file!("look.js", SCRIPT),
    page_file!("render-gl.js", SCRIPT),
    page_file!("render-2d.js", SCRIPT),
    Asset {
        path: "/hairsim_viewer.wasm",
        content_type: "application/wasm",
        bytes: WASM,
    },
    Asset {
        path: "/hairsim_viewer_simd.wasm",
        content_type: "application/wasm",
        bytes: WASM_SIMD,
    },
];

/// A path's last component, as the page names the file.
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    )
}

/// The scene the page opens first, as the page will load it: SCENE as `hairsim run` takes it
/// (a built-in name, a `.hair`/`.tfx` file or a scene file), read and checked here with the
/// native run's checks so that a bad SCENE fails on the command line.
///
/// # Errors
/// SCENE is none of these, fails the scene's checks, or a file cannot be read.
pub fn initial(spec: &str) -> Result<Source> {
    let loaded = load(spec, &HairFileOptions::default())?;
    if let Some(name) = loaded.source.strip_prefix("builtin:") {
        return Source::builtin(name).map_err(|e| anyhow!(e));
    }
    let path = Path::new(spec);
    if crate::hairfile::is_hair_file(spec) {
        let bytes = std::fs::read(path).with_context(|| format!("{spec}: cannot read"))?;
        return Ok(Source::HairFile {
            name: file_name(path),
            bytes,
        });
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("{spec}: cannot read"))?;
    let hair = match &loaded.scene.hair {
        Some(HairSpec::File(file)) => {
            let hair_path = hair_file_path(file, Path::new("."))
                .map_err(|e| anyhow!("{spec}: {}: {}", e.field, e.message))?;
            let bytes = std::fs::read(&hair_path)
                .with_context(|| format!("{}: cannot read", hair_path.display()))?;
            Some((file_name(&hair_path), bytes))
        }
        _ => None,
    };
    Ok(Source::SceneFile {
        name: file_name(path),
        text,
        hair,
    })
}

/// `/initial.json`: what the page loads first and how.
fn description(initial: &Source) -> String {
    match initial {
        Source::Builtin(name) => json!({ "kind": "builtin", "name": name }),
        Source::HairFile { name, .. } => json!({ "kind": "hair", "name": name }),
        Source::SceneFile { name, hair, .. } => json!({
            "kind": "scene",
            "name": name,
            "hair": hair.as_ref().map(|(hair_name, _)| hair_name),
        }),
    }
    .to_string()
}

/// `/initial`: the hair file's bytes or the scene file's text.
fn content(initial: &Source) -> Option<&[u8]> {
    match initial {
        Source::Builtin(_) => None,
        Source::HairFile { bytes, .. } => Some(bytes),
        Source::SceneFile { text, .. } => Some(text.as_bytes()),
    }
}

/// `/initial-hair`: the scene file's hair file.
fn hair(initial: &Source) -> Option<&[u8]> {
    match initial {
        Source::SceneFile {
            hair: Some((_, bytes)),
            ..
        } => Some(bytes),
        _ => None,
    }
}

/// The page's server on 127.0.0.1.
pub struct Server {
    http: tiny_http::Server,
    initial: Source,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0: a free port).
    ///
    /// # Errors
    /// The harness was built without the page's module, or the port cannot be bound.
    pub fn bind(port: u16, initial: Source) -> Result<Server> {
        if WASM.is_empty() {
            bail!(
                "this hairsim was built without the viewer's simulation: run `rustup target add \
                 wasm32-unknown-unknown` and build hairsim again"
            );
        }
        let http = tiny_http::Server::http(("127.0.0.1", port))
            .map_err(|e| anyhow!("cannot listen on 127.0.0.1:{port}: {e}"))?;
        Ok(Server { http, initial })
    }

    /// The page's address.
    #[must_use]
    pub fn url(&self) -> String {
        match self.http.server_addr().to_ip() {
            Some(address) => format!("http://{address}/"),
            None => "http://127.0.0.1/".into(),
        }
    }

    /// Answers requests until the process ends.
    ///
    /// # Errors
    /// The listening socket fails.
    pub fn serve(&self) -> Result<()> {
        for request in self.http.incoming_requests() {
            self.answer(request);
        }
        bail!("the server at {} stopped listening", self.url())
    }

    /// Answers one request; a client that has gone away is not the server's problem.
    fn answer(&self, request: tiny_http::Request) {
        let (status, content_type, body) = self.lookup(request.method(), request.url());
        let header = tiny_http::Header::from_bytes("Content-Type", content_type)
            .expect("a constant, valid header");
        let response = tiny_http::Response::from_data(body)
            .with_status_code(status)
            .with_header(header);
        let _ = request.respond(response);
    }

    /// The status, content type and body for a request.
    fn lookup(&self, method: &tiny_http::Method, url: &str) -> (u16, &'static str, Vec<u8>) {
        const TEXT: &str = "text/plain; charset=utf-8";
        if *method != tiny_http::Method::Get {
            return (405, TEXT, b"only GET".to_vec());
        }
        let path = match url.split(['?', '#']).next().unwrap_or(url) {
            "/" => "/index.html",
            path => path,
        };
        if let Some(asset) = ASSETS.iter().find(|a| a.path == path) {
            return (200, asset.content_type, asset.bytes.to_vec());
        }
        let initial = match path {
            "/initial.json" => Some(description(&self.initial).into_bytes()),
            "/initial" => content(&self.initial).map(<[u8]>::to_vec),
            "/initial-hair" => hair(&self.initial).map(<[u8]>::to_vec),
            _ => None,
        };
        match initial {
            Some(body) => (200, "application/octet-stream", body),
            None => (404, TEXT, format!("{path}: not found").into_bytes()),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::{Read, Write};
    use std::net::TcpStream;

    use super::*;

    /// Status line and body of `GET path` from a server on another thread.
    fn get(url: &str, path: &str) -> (String, Vec<u8>) {
        let address = url.trim_start_matches("http://").trim_end_matches('/');
        let mut stream = TcpStream::connect(address).unwrap();
        write!(stream, "GET {path} HTTP/1.0\r\nHost: {address}\r\n\r\n").unwrap();
        let mut reply = Vec::new();
        stream.read_to_end(&mut reply).unwrap();
        let split = reply.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
        let head = String::from_utf8_lossy(&reply[..split]).to_string();
        (
            head.lines().next().unwrap().to_string(),
            reply[split + 4..].to_vec(),
        )
    }

    #[test]
    fn serves_the_page_the_module_and_the_initial_scene_only() {
        if WASM.is_empty() {
            // Built without the wasm target: binding must say so rather than serve a dead page.
            let error = Server::bind(0, initial("firmware").unwrap()).err().unwrap();
            assert!(error.to_string().contains("rustup target add"));
            return;
        }
        let server = Server::bind(0, initial("firmware-dftl").unwrap()).unwrap();
        let url = server.url();
        assert!(url.starts_with("http://127.0.0.1:"), "{url}");
        std::thread::spawn(move || server.serve());
        let (status, body) = get(&url, "/");
        assert!(status.contains("200"), "{status}");
        assert!(String::from_utf8_lossy(&body).contains("viewer.js"));
        for module in ["/hairsim_viewer.wasm", "/hairsim_viewer_simd.wasm"] {
            let (status, body) = get(&url, module);
            assert!(status.contains("200"), "{module}: {status}");
            assert_eq!(&body[..4], b"\0asm", "{module}");
        }
        let (_, body) = get(&url, "/initial.json?x=1");
        assert_eq!(body, br#"{"kind":"builtin","name":"firmware-dftl"}"#);
        let (status, _) = get(&url, "/initial");
        assert!(status.contains("404"), "{status}");
        let (status, _) = get(&url, "/../Cargo.toml");
        assert!(status.contains("404"), "{status}");
    }

    #[test]
    fn a_bad_scene_fails_before_serving() {
        let error = initial("no-such-scene").unwrap_err().to_string();
        assert!(error.contains("no such scene"), "{error}");
    }

    #[test]
    fn a_hair_file_is_served_as_read() {
        // CI sets HAIRSIM_SAMPLES; the sample files are not part of the repository.
        let Some(samples) = std::env::var_os("HAIRSIM_SAMPLES") else {
            return;
        };
        let hair = Path::new(&samples).join("sintel_hair.tfx");
        let initial = initial(hair.to_str().unwrap()).unwrap();
        assert!(description(&initial).contains(r#""kind":"hair","name":"sintel_hair.tfx""#));
        assert_eq!(content(&initial).unwrap(), std::fs::read(&hair).unwrap());
    }
}
