//! The core's layers: every module of `core/src` sits in one layer, and uses only modules of
//! its own layer or the layers below it, with no circle among them.
//!
//! The layer of each module is declared once, in the Markdown table of
//! `docs/architecture.md` between `<!-- layers:begin -->` and `<!-- layers:end -->` (columns:
//! the module path as `crate::`-relative segments, then its layer as a number and a name). This
//! test reads that table, scans the non-test code of every file of `core/src` for the paths it
//! uses, and fails on
//!
//! * a module missing from the table (or a row naming no module),
//! * an upward path: a module using a module of a higher layer,
//! * a circle among modules, even within one layer.
//!
//! The scanner is a small hand-written tokenizer, not a Rust parser. It resolves every
//! `crate::`, `super::` and `self::` path, and paths that start with a child module the scope
//! declares (`mod lane;` then `lane::V3`), in `use` and `pub use` lines (grouped ones like
//! `use crate::{a, b::{c, d}}` included) and inline (`crate::rod::twist::newton(…)`), with
//! `super::` counted from the inline module it is written in. Each path goes to the longest
//! module of the table it starts with (`crate::dftl::lane::V3` to `dftl::lane` if that is a
//! row, else to `dftl`); a path to the crate root (`crate::Real`) goes to `crate`, the root's
//! own row. Comments, string literals and test code are skipped: files named `tests.rs`, and
//! everything from a file's first `#[cfg(test)]` line on.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;

/// The marker lines around the table in `docs/architecture.md`.
const BEGIN: &str = "<!-- layers:begin -->";
const END: &str = "<!-- layers:end -->";

/// Module path (segments joined by `::`, the root is `crate`) → layer.
type Table = BTreeMap<String, u32>;

/// What the check found wrong.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Violation {
    /// A module of the source tree that the table leaves out.
    Missing { module: String },
    /// A row of the table naming no module of the source tree.
    Stale { module: String },
    /// `from` (layer `from_layer`) uses `to` (a higher layer) through `path`.
    Upward {
        from: String,
        from_layer: u32,
        to: String,
        to_layer: u32,
        path: String,
    },
    /// Modules that use each other in a circle: every module of the knot (by name), and one
    /// circle through them to follow.
    Circle {
        modules: Vec<String>,
        example: Vec<String>,
    },
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Violation::Missing { module } => {
                write!(f, "module `{module}` is missing from the layer table")
            }
            Violation::Stale { module } => {
                write!(
                    f,
                    "the layer table names `{module}`, which is no module of the core"
                )
            }
            Violation::Upward {
                from,
                from_layer,
                to,
                to_layer,
                path,
            } => write!(
                f,
                "upward path: `{from}` (layer {from_layer}) uses `{to}` (layer {to_layer}) \
                 through `{path}`"
            ),
            Violation::Circle { modules, example } => write!(
                f,
                "circle among {}: for one, {} -> {}",
                modules.join(", "),
                example.join(" -> "),
                example[0]
            ),
        }
    }
}

/// Reads the table between the markers: the first cell of each row is the module path
/// (backticks allowed), the second starts with the layer number.
fn parse_table(markdown: &str) -> Result<Table, String> {
    let start = markdown
        .find(BEGIN)
        .ok_or_else(|| format!("no `{BEGIN}` line"))?;
    let block = &markdown[start + BEGIN.len()..];
    let end = block.find(END).ok_or_else(|| format!("no `{END}` line"))?;
    let mut table = Table::new();
    for line in block[..end].lines() {
        let line = line.trim();
        if !line.starts_with('|') {
            continue;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        let module = cells[0].trim_matches('`').trim();
        let layer = cells.get(1).copied().unwrap_or("");
        let digits: String = layer.chars().take_while(char::is_ascii_digit).collect();
        if module.is_empty() || module == "module" || module.starts_with('-') {
            continue; // header or separator row
        }
        let layer: u32 = digits
            .parse()
            .map_err(|_| format!("row `{line}`: the layer cell must start with a number"))?;
        if table.insert(module.to_string(), layer).is_some() {
            return Err(format!("module `{module}` has two rows"));
        }
    }
    if table.is_empty() {
        return Err("the table between the markers has no rows".into());
    }
    Ok(table)
}

/// The module a file of `core/src` defines: `lib.rs` is `crate`, `a/mod.rs` and `a.rs` are
/// `a`, `a/b.rs` is `a::b`.
fn module_of(relative: &str) -> String {
    let path = relative.trim_end_matches(".rs");
    let mut segments: Vec<&str> = path.split('/').collect();
    if segments.last() == Some(&"mod") {
        segments.pop();
    }
    if segments == ["lib"] {
        return "crate".into();
    }
    segments.join("::")
}

/// A file's text up to its first `#[cfg(test)]` line.
fn non_test(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        if line.contains("#[cfg(test)]") {
            break;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// `text` with comments removed and string and character literals blanked, so that only
/// code is left to scan.
fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !ident_before(&chars, i) {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                match chars.get(j) {
                    None => break,
                    Some('"') if (0..hashes).all(|h| chars.get(j + 1 + h) == Some(&'#')) => {
                        j += 1 + hashes;
                        break;
                    }
                    _ => j += 1,
                }
            }
            out.push_str("\"\"");
            i = j;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == '\'' && (chars.get(i + 2) == Some(&'\'') || next == Some('\\')) {
            // A character literal ('x' or '\n', '\''), not a lifetime.
            i += 1;
            while i < chars.len() && chars[i] != '\'' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("' '");
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// Whether the character before `i` continues an identifier (so `r` there is no raw string).
fn ident_before(chars: &[char], i: usize) -> bool {
    i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_')
}

/// The tokens the scanner cares about: identifiers (keywords included), `::`, and every other
/// punctuation character on its own.
fn tokens(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else if c.is_whitespace() {
            i += 1;
        } else {
            out.push(c.to_string());
            i += 1;
        }
    }
    out
}

/// A path written in a module, resolved to segments from the crate root.
#[derive(Debug)]
struct Use {
    /// The scope it is written in (file module plus inline modules), from the root.
    scope: Vec<String>,
    /// The path from the root (`crate::a::b` is `[a, b]`; the root itself is `[]`).
    target: Vec<String>,
    /// The path as written.
    written: String,
}

/// Every path of `code` (a file of module `module`) that names a module of this crate.
fn uses(module: &str, code: &str) -> Vec<Use> {
    let tokens = tokens(code);
    let file_scope: Vec<String> = if module == "crate" {
        Vec::new()
    } else {
        module.split("::").map(String::from).collect()
    };
    // Module scopes open at each brace depth (`None` for other braces), and the child modules
    // each scope declares.
    let mut braces: Vec<Option<String>> = Vec::new();
    let mut children: BTreeMap<Vec<String>, BTreeSet<String>> = BTreeMap::new();
    // First pass: the child modules each scope declares (`mod x;` or `mod x {`).
    {
        let mut scope = file_scope.clone();
        let mut stack: Vec<bool> = Vec::new();
        let mut k = 0;
        while k < tokens.len() {
            let t = tokens[k].as_str();
            if t == "mod" && k + 1 < tokens.len() {
                let name = tokens[k + 1].clone();
                children
                    .entry(scope.clone())
                    .or_default()
                    .insert(name.clone());
                if tokens.get(k + 2).map(String::as_str) == Some("{") {
                    scope.push(name);
                    stack.push(true);
                    k += 3;
                    continue;
                }
            } else if t == "{" {
                stack.push(false);
            } else if t == "}" && stack.pop() == Some(true) {
                scope.pop();
            }
            k += 1;
        }
    }
    let mut out = Vec::new();
    let mut scope = file_scope.clone();
    let mut k = 0;
    while k < tokens.len() {
        let t = tokens[k].as_str();
        match t {
            "mod" if tokens.get(k + 2).map(String::as_str) == Some("{") => {
                scope.push(tokens[k + 1].clone());
                braces.push(Some(tokens[k + 1].clone()));
                k += 3;
                continue;
            }
            "{" => braces.push(None),
            "}" => {
                if let Some(Some(_)) = braces.pop() {
                    scope.pop();
                }
            }
            "use" => {
                let end = (k..tokens.len())
                    .find(|&j| tokens[j] == ";")
                    .unwrap_or(tokens.len());
                let mut leaves = Vec::new();
                use_tree(&tokens[k + 1..end], &[], &mut leaves);
                for leaf in leaves {
                    let declared = children.get(&scope).cloned().unwrap_or_default();
                    if let Some(target) = resolve(&scope, &leaf, &declared) {
                        out.push(Use {
                            scope: scope.clone(),
                            target,
                            written: leaf.join("::"),
                        });
                    }
                }
                k = end + 1;
                continue;
            }
            _ => {
                let after_path = k > 0 && tokens[k - 1] == "::";
                let declared = children.get(&scope).cloned().unwrap_or_default();
                let starts = matches!(t, "crate" | "super" | "self") || declared.contains(t);
                if starts && !after_path && tokens.get(k + 1).map(String::as_str) == Some("::") {
                    let mut path = vec![t.to_string()];
                    let mut j = k + 1;
                    while tokens.get(j).map(String::as_str) == Some("::")
                        && tokens
                            .get(j + 1)
                            .is_some_and(|s| s.chars().all(|c| c.is_alphanumeric() || c == '_'))
                    {
                        path.push(tokens[j + 1].clone());
                        j += 2;
                    }
                    if let Some(target) = resolve(&scope, &path, &declared) {
                        out.push(Use {
                            scope: scope.clone(),
                            target,
                            written: path.join("::"),
                        });
                    }
                    k = j;
                    continue;
                }
            }
        }
        k += 1;
    }
    out
}

/// Expands a `use` tree (the tokens after `use`, up to `;`) into its leaf paths:
/// `crate::{a, b::{c, self}}` gives `crate::a`, `crate::b::c`, `crate::b`.
fn use_tree(tokens: &[String], prefix: &[String], leaves: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    let mut k = 0;
    while k < tokens.len() {
        match tokens[k].as_str() {
            "::" => {}
            "{" => {
                // The group runs to the matching brace; its items are split at top-level commas.
                let mut depth = 0;
                let mut item_start = k + 1;
                let mut j = k;
                while j < tokens.len() {
                    match tokens[j].as_str() {
                        "{" => depth += 1,
                        "}" => {
                            depth -= 1;
                            if depth == 0 {
                                use_tree(&tokens[item_start..j], &path, leaves);
                                break;
                            }
                        }
                        "," if depth == 1 => {
                            use_tree(&tokens[item_start..j], &path, leaves);
                            item_start = j + 1;
                        }
                        _ => {}
                    }
                    j += 1;
                }
                return;
            }
            "as" => break,
            "*" => break,
            "self" if !path.is_empty() => {}
            word => path.push(word.to_string()),
        }
        k += 1;
    }
    if path.len() > prefix.len() || !path.is_empty() {
        leaves.push(path);
    }
}

/// The path `path`, written in `scope` (which declares the child modules `children`),
/// from the crate root; `None` for a path outside the crate (`core::…`, `glam::…`).
fn resolve(scope: &[String], path: &[String], children: &BTreeSet<String>) -> Option<Vec<String>> {
    let first = path.first()?.as_str();
    let mut base: Vec<String>;
    let mut rest = &path[1..];
    match first {
        "crate" => base = Vec::new(),
        "self" => base = scope.to_vec(),
        "super" => {
            base = scope.to_vec();
            base.pop();
            while rest.first().map(String::as_str) == Some("super") {
                base.pop();
                rest = &rest[1..];
            }
        }
        name if children.contains(name) => {
            base = scope.to_vec();
            rest = path;
        }
        _ => return None,
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The row of `table` a path from the root belongs to: its longest prefix with a row, or the
/// root `crate`.
fn row_of(table: &Table, target: &[String]) -> String {
    (1..=target.len())
        .rev()
        .map(|len| target[..len].join("::"))
        .find(|m| table.contains_key(m))
        .unwrap_or_else(|| "crate".into())
}

/// Checks the sources (`(relative path under core/src, text)`) against the table.
fn check(table: &Table, sources: &[(String, String)]) -> Vec<Violation> {
    let mut violations = BTreeSet::new();
    let mut modules = BTreeSet::new();
    // Edges between rows, each with one path that makes it.
    let mut edges: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for (file, text) in sources {
        if file.ends_with("tests.rs") {
            continue;
        }
        let module = module_of(file);
        modules.insert(module.clone());
        if !table.contains_key(&module) {
            violations.insert(Violation::Missing {
                module: module.clone(),
            });
            continue;
        }
        let code = code_only(&non_test(text));
        for u in uses(&module, &code) {
            let from = row_of(table, &u.scope);
            let to = row_of(table, &u.target);
            if from == to {
                continue;
            }
            edges
                .entry(from.clone())
                .or_default()
                .entry(to.clone())
                .or_insert_with(|| u.written.clone());
        }
    }
    for module in table.keys() {
        if !modules.contains(module) {
            violations.insert(Violation::Stale {
                module: module.clone(),
            });
        }
    }
    for (from, targets) in &edges {
        for (to, path) in targets {
            let (Some(&from_layer), Some(&to_layer)) = (table.get(from), table.get(to)) else {
                continue;
            };
            if to_layer > from_layer {
                violations.insert(Violation::Upward {
                    from: from.clone(),
                    from_layer,
                    to: to.clone(),
                    to_layer,
                    path: path.clone(),
                });
            }
        }
    }
    for (modules, example) in circles(&edges) {
        violations.insert(Violation::Circle { modules, example });
    }
    violations.into_iter().collect()
}

/// The strongly connected components of more than one module (Tarjan): each one's modules by
/// name, and a circle through them to follow.
fn circles(edges: &BTreeMap<String, BTreeMap<String, String>>) -> Vec<(Vec<String>, Vec<String>)> {
    struct Search<'a> {
        edges: &'a BTreeMap<String, BTreeMap<String, String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        components: Vec<Vec<String>>,
    }
    impl<'a> Search<'a> {
        fn visit(&mut self, v: &'a str) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.edges.get(v).into_iter().flat_map(|t| t.keys()) {
                let w = w.as_str();
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.on_stack.contains(w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    component.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    self.components.push(component);
                }
            }
        }
    }
    let mut search = Search {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        components: Vec::new(),
    };
    for v in edges.keys() {
        if !search.index.contains_key(v.as_str()) {
            search.visit(v);
        }
    }
    search
        .components
        .into_iter()
        .map(|component| {
            let example = follow(edges, component.clone());
            let mut modules = component;
            modules.sort();
            (modules, example)
        })
        .collect()
}

/// The modules of a strongly connected component in an order that follows its edges from
/// its first module (by name) back to it.
fn follow(
    edges: &BTreeMap<String, BTreeMap<String, String>>,
    component: Vec<String>,
) -> Vec<String> {
    let members: BTreeSet<String> = component.into_iter().collect();
    let start = members.iter().next().cloned().unwrap_or_default();
    // Breadth-first from `start` to the predecessor of `start` within the component.
    let mut previous: BTreeMap<String, String> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start.clone()]);
    let mut seen = BTreeSet::from([start.clone()]);
    while let Some(v) = queue.pop_front() {
        for w in edges.get(&v).into_iter().flat_map(|t| t.keys()) {
            if w == &start {
                let mut path = vec![v.clone()];
                while let Some(p) = previous.get(path.last().unwrap()) {
                    path.push(p.clone());
                }
                path.reverse();
                return path;
            }
            if members.contains(w) && seen.insert(w.clone()) {
                previous.insert(w.clone(), v.clone());
                queue.push_back(w.clone());
            }
        }
    }
    members.into_iter().collect()
}

/// Every `.rs` file under `dir`, as `(path relative to dir with '/', text)`.
fn sources(dir: &Path) -> Vec<(String, String)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            if path.is_dir() {
                walk(root, &path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let relative = path.strip_prefix(root).unwrap();
                let relative = relative
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
                    .join("/");
                out.push((relative, std::fs::read_to_string(&path).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out
}

#[test]
fn the_core_keeps_its_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let doc = root.join("docs/architecture.md");
    let markdown =
        std::fs::read_to_string(&doc).unwrap_or_else(|e| panic!("{}: {e}", doc.display()));
    let table = parse_table(&markdown).unwrap_or_else(|e| panic!("{}: {e}", doc.display()));
    let files = sources(&root.join("core/src"));
    assert!(files.len() > 20, "found only {} files", files.len());
    let violations = check(&table, &files);
    let report: Vec<String> = violations.iter().map(ToString::to_string).collect();
    assert!(
        violations.is_empty(),
        "the core's layers ({}):\n{}",
        doc.display(),
        report.join("\n")
    );
}

/// A table and sources written inline: `(file, text)` pairs.
fn synthetic(rows: &[(&str, u32)], files: &[(&str, &str)]) -> Vec<Violation> {
    let table: Table = rows.iter().map(|&(m, l)| (m.to_string(), l)).collect();
    let sources: Vec<(String, String)> = files
        .iter()
        .map(|&(f, t)| (f.to_string(), t.to_string()))
        .collect();
    check(&table, &sources)
}

#[test]
fn an_upward_path_fails() {
    let rows = [("crate", 3), ("math", 1), ("strand", 2), ("world", 3)];
    let files = [
        ("lib.rs", "pub mod math; pub mod strand; pub mod world;"),
        ("math.rs", "pub type Real = f32;"),
        // Model data calling into a pipeline, inline and in a grouped `use`.
        (
            "strand.rs",
            "use crate::{math::Real, world::{World}};\n\
             fn f() { let _ = crate::world::step(); }",
        ),
        ("world.rs", "use crate::math::Real;"),
    ];
    let violations = synthetic(&rows, &files);
    assert!(
        matches!(
            violations.as_slice(),
            [Violation::Upward { from, to, from_layer: 2, to_layer: 3, .. }]
                if from == "strand" && to == "world"
        ),
        "{violations:?}"
    );
    // A path to the crate root's re-exports is a path to the root, the highest layer.
    let files = [
        ("lib.rs", "pub mod math; pub use math::Real;"),
        ("math.rs", ""),
        ("strand.rs", "fn f(x: crate::Real) {}"),
        ("world.rs", ""),
    ];
    let violations = synthetic(&rows, &files);
    assert!(
        matches!(violations.as_slice(), [Violation::Upward { to, .. }] if to == "crate"),
        "{violations:?}"
    );
}

#[test]
fn a_circle_fails_even_within_one_layer() {
    let rows = [
        ("crate", 3),
        ("rod", 2),
        ("rod::energy", 2),
        ("rod::twist", 2),
    ];
    let files = [
        ("lib.rs", "pub mod rod;"),
        ("rod/mod.rs", "pub mod energy; pub mod twist;"),
        ("rod/energy.rs", "use super::twist::binormal_direction;"),
        (
            "rod/twist.rs",
            "pub fn binormal_direction() {}\nfn g() { super::energy::rest(); }",
        ),
    ];
    let violations = synthetic(&rows, &files);
    assert_eq!(
        violations,
        [Violation::Circle {
            modules: vec!["rod::energy".into(), "rod::twist".into()],
            example: vec!["rod::energy".into(), "rod::twist".into()],
        }]
    );
    // A parent and its child: `mod.rs` re-exporting a child that uses the parent.
    let files = [
        ("lib.rs", "pub mod rod;"),
        (
            "rod/mod.rs",
            "pub mod energy; pub mod twist; pub use energy::E;",
        ),
        ("rod/energy.rs", "use super::Clamped;"),
        ("rod/twist.rs", ""),
    ];
    let violations = synthetic(&rows, &files);
    assert_eq!(
        violations,
        [Violation::Circle {
            modules: vec!["rod".into(), "rod::energy".into()],
            example: vec!["rod".into(), "rod::energy".into()],
        }]
    );
}

#[test]
fn a_module_missing_from_the_table_fails() {
    let rows = [("crate", 2), ("math", 1)];
    let files = [
        ("lib.rs", "pub mod math; pub mod guard;"),
        ("math.rs", ""),
        ("guard.rs", "use crate::math::Real;"),
    ];
    assert_eq!(
        synthetic(&rows, &files),
        [Violation::Missing {
            module: "guard".into()
        }]
    );
    // And a row for no module.
    let rows = [("crate", 2), ("math", 1), ("gone", 1)];
    let files = [("lib.rs", "pub mod math;"), ("math.rs", "")];
    assert_eq!(
        synthetic(&rows, &files),
        [Violation::Stale {
            module: "gone".into()
        }]
    );
}

#[test]
fn the_scanner_resolves_what_it_should_and_skips_what_it_should() {
    let rows = [
        ("crate", 4),
        ("math", 1),
        ("strand", 2),
        ("scenes", 4),
        ("dftl", 3),
        ("dftl::lane", 1),
        ("dftl::predict", 3),
    ];
    let files = [
        ("lib.rs", "pub mod math;"),
        // `super::` from an inline module is its file's module; comments, strings and test
        // code do not count.
        (
            "math.rs",
            "// use crate::strand::Strand;\n/* crate::scenes */\n\
             const S: &str = \"crate::scenes::x\";\nconst C: char = '\"';\n\
             pub mod inner { use super::*; fn f() -> char { 'x' } }\n\
             #[cfg(test)]\nmod tests { use crate::scenes::firmware; }",
        ),
        ("strand.rs", "use crate::math::{self, Real};"),
        (
            "scenes.rs",
            "pub mod firmware { use super::*; use crate::strand::Strand; }",
        ),
        (
            "dftl/mod.rs",
            "pub mod lane; pub mod predict; use lane::V3; use self::predict::x;",
        ),
        // `super::lane` goes to `dftl::lane`, its own row; `super::Setup` to `dftl`, whose
        // `use self::predict` closes a circle.
        ("dftl/predict.rs", "use super::{lane::{Lane, V3}, Setup};"),
        ("dftl/lane.rs", "pub struct V3;"),
        ("dftl/tests.rs", "use crate::scenes::firmware;"),
    ];
    let violations = synthetic(&rows, &files);
    assert_eq!(
        violations,
        [Violation::Circle {
            modules: vec!["dftl".into(), "dftl::predict".into()],
            example: vec!["dftl".into(), "dftl::predict".into()],
        }],
        "{violations:#?}"
    );
}
