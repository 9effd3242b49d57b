//! The files of `src/run/` import one another one way (#47): no file reaches back, directly
//! or through a cycle, to a file that imports it.
//!
//! The test reads the sources as text. A file `src/run/a.rs` depends on `src/run/b.rs`
//! when its code (comments and string literals left out: doc links do not import)
//! names a path into `b`: `crate::run::b::…`, `super::b::…`, a grouped import such as
//! `use crate::run::{b::X, c}`, or an item of `b` that `src/lib.rs` re-exports at the
//! crate root (`crate::RunResult` is `crate::run::runner::RunResult`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Module name → the sibling modules it names.
type Graph = BTreeMap<String, BTreeSet<String>>;

/// `source` with its comments blanked out and its string and character literals emptied,
/// so that what is left is code.
fn code_only(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < chars.len() {
        let (c, next) = (chars[i], chars.get(i + 1).copied());
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            i = block_comment_end(&chars, i);
            out.push(' ');
        } else if c == 'r' && matches!(next, Some('"' | '#')) && !ident_before(&chars, i) {
            i = raw_string_end(&chars, i);
            out.push_str("\"\"");
        } else if c == '"' {
            i = string_end(&chars, i);
            out.push_str("\"\"");
        } else if c == '\'' {
            i = char_literal_end(&chars, i);
            out.push(' ');
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident_before(chars: &[char], i: usize) -> bool {
    i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_')
}

/// Past the (possibly nested) block comment opening at `i`.
fn block_comment_end(chars: &[char], mut i: usize) -> usize {
    let mut depth = 0;
    while i < chars.len() {
        if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    i
}

/// Past the string literal opening at `i` (escapes honoured).
fn string_end(chars: &[char], mut i: usize) -> usize {
    i += 1;
    while i < chars.len() && chars[i] != '"' {
        i += if chars[i] == '\\' { 2 } else { 1 };
    }
    i + 1
}

/// Past the raw string literal `r#…"…"#…` opening at `i`.
fn raw_string_end(chars: &[char], mut i: usize) -> usize {
    i += 1;
    let mut hashes = 0;
    while chars.get(i) == Some(&'#') {
        hashes += 1;
        i += 1;
    }
    i += 1;
    while i < chars.len() {
        let closes = chars[i] == '"' && (1..=hashes).all(|k| chars.get(i + k) == Some(&'#'));
        if closes {
            return i + 1 + hashes;
        }
        i += 1;
    }
    i
}

/// Past the character literal opening at `i`, or just past the `'` of a lifetime.
fn char_literal_end(chars: &[char], i: usize) -> usize {
    match (chars.get(i + 1), chars.get(i + 2)) {
        (Some('\\'), _) => {
            let mut j = i + 2;
            while j < chars.len() && chars[j] != '\'' {
                j += 1;
            }
            j + 1
        }
        (Some(_), Some('\'')) => i + 3,
        _ => i + 1,
    }
}

/// A path named in code, its segments and the name it is imported as (`as x`).
#[derive(Debug, Clone, PartialEq)]
struct NamedPath {
    segments: Vec<String>,
    alias: Option<String>,
}

/// Every path of two or more segments in `code` (from [`code_only`]), grouped imports
/// (`a::{b::C, d}`) expanded into one path each.
fn paths(code: &str) -> Vec<NamedPath> {
    let tokens = tokenize(code);
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let after_colons = i > 0 && tokens[i - 1] == "::";
        if is_ident(&tokens[i])
            && !after_colons
            && tokens.get(i + 1).map(String::as_str) == Some("::")
        {
            i = path_at(&tokens, i, Vec::new(), &mut out);
        } else {
            i += 1;
        }
    }
    out
}

/// Identifiers, `::`, and every other character on its own.
fn tokenize(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            tokens.push(chars[start..i].iter().collect());
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            tokens.push("::".to_string());
            i += 2;
        } else {
            if !c.is_whitespace() {
                tokens.push(c.to_string());
            }
            i += 1;
        }
    }
    tokens
}

fn is_ident(token: &str) -> bool {
    token
        .chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// Reads the path starting at token `i` (after the segments `prefix`) into `out`;
/// returns the index past it.
fn path_at(
    tokens: &[String],
    mut i: usize,
    mut prefix: Vec<String>,
    out: &mut Vec<NamedPath>,
) -> usize {
    loop {
        match tokens.get(i).map(String::as_str) {
            Some("{") => return group_at(tokens, i + 1, &prefix, out),
            Some(t) if is_ident(t) => prefix.push(t.to_string()),
            _ => break,
        }
        i += 1;
        if tokens.get(i).map(String::as_str) != Some("::") {
            break;
        }
        i += 1;
    }
    let alias = match tokens.get(i).map(String::as_str) {
        Some("as") => {
            i += 2;
            tokens.get(i - 1).cloned()
        }
        _ => None,
    };
    if prefix.len() >= 2 {
        out.push(NamedPath {
            segments: prefix,
            alias,
        });
    }
    i
}

/// Reads the members of a `{…}` group (its `{` just before token `i`) under `prefix`;
/// returns the index past its `}`.
fn group_at(tokens: &[String], mut i: usize, prefix: &[String], out: &mut Vec<NamedPath>) -> usize {
    while i < tokens.len() {
        match tokens[i].as_str() {
            "}" => return i + 1,
            "," | "*" | "self" => i += 1,
            t if is_ident(t) => i = path_at(tokens, i, prefix.to_vec(), out),
            _ => i += 1,
        }
    }
    i
}

/// The names `src/lib.rs` re-exports from `run` at the crate root, each with the module
/// of `src/run/` it comes from (`RunResult` → `runner`; a module re-exported as itself or
/// under an alias → that module).
fn root_reexports(lib: &str) -> BTreeMap<String, String> {
    let mut names = BTreeMap::new();
    for path in paths(&code_only(lib)) {
        let s = &path.segments;
        if s[0] != "run" {
            continue;
        }
        let name = path.alias.clone().unwrap_or_else(|| s[s.len() - 1].clone());
        names.insert(name, s[1].clone());
    }
    names
}

/// The module of `src/run/` that `path`, named in the file of module `from`, points into,
/// if it is another one than `from`.
fn target(
    path: &NamedPath,
    modules: &BTreeSet<String>,
    reexports: &BTreeMap<String, String>,
    from: &str,
) -> Option<String> {
    let s: Vec<&str> = path.segments.iter().map(String::as_str).collect();
    let module = match s.as_slice() {
        ["crate", "run", m, ..] | ["super", m, ..] => Some(m.to_string()),
        ["crate", "run"] => None,
        ["crate", name, ..] => reexports.get(*name).cloned(),
        _ => None,
    };
    module.filter(|m| modules.contains(m) && m != from)
}

/// The import graph of the module files `files` (name → source), `lib` being the crate
/// root's source.
fn graph(files: &BTreeMap<String, String>, lib: &str) -> Graph {
    let modules: BTreeSet<String> = files.keys().cloned().collect();
    let reexports = root_reexports(lib);
    let mut graph = Graph::new();
    for (name, source) in files {
        let code = code_only(source);
        let edges = paths(&code)
            .iter()
            .filter_map(|p| target(p, &modules, &reexports, name))
            .collect();
        graph.insert(name.clone(), edges);
    }
    graph
}

/// A cycle of `graph` (its modules in order, the first repeated at the end), if any.
fn cycle(graph: &Graph) -> Option<Vec<String>> {
    // 0: not seen; 1: on the current path; 2: done (no cycle through it).
    let mut state: BTreeMap<&str, u8> = BTreeMap::new();
    let mut path = Vec::new();
    for start in graph.keys() {
        if let Some(c) = visit(graph, start, &mut state, &mut path) {
            return Some(c);
        }
    }
    None
}

fn visit<'a>(
    graph: &'a Graph,
    node: &'a str,
    state: &mut BTreeMap<&'a str, u8>,
    path: &mut Vec<&'a str>,
) -> Option<Vec<String>> {
    match state.get(node) {
        Some(2) => return None,
        Some(1) => {
            let from = path.iter().position(|n| *n == node).unwrap_or(0);
            let mut c: Vec<String> = path[from..].iter().map(|s| s.to_string()).collect();
            c.push(node.to_string());
            return Some(c);
        }
        _ => {}
    }
    state.insert(node, 1);
    path.push(node);
    for next in graph.get(node).into_iter().flatten() {
        if let Some(c) = visit(graph, next, state, path) {
            return Some(c);
        }
    }
    path.pop();
    state.insert(node, 2);
    None
}

/// `src/run/*.rs` but `mod.rs`, by module name.
fn run_files() -> BTreeMap<String, String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/run");
    let mut files = BTreeMap::new();
    for entry in std::fs::read_dir(&dir).expect("src/run/") {
        let path = entry.expect("entry").path();
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        if path.extension().is_some_and(|e| e == "rs") && stem != "mod" {
            let source = std::fs::read_to_string(&path).expect("a source file");
            files.insert(stem.to_string(), source);
        }
    }
    files
}

fn lib_source() -> String {
    let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs");
    std::fs::read_to_string(lib).expect("src/lib.rs")
}

#[test]
fn run_files_import_one_another_one_way() {
    let graph = graph(&run_files(), &lib_source());
    let edges: Vec<String> = graph
        .iter()
        .flat_map(|(a, to)| to.iter().map(move |b| format!("{a} -> {b}")))
        .collect();
    println!("{}", edges.join("\n"));
    // Not vacuous: the files are there and the reading finds the loop's own imports.
    for module in [
        "runner",
        "main_loop",
        "tally",
        "checkpoint",
        "observe",
        "control",
    ] {
        assert!(graph.contains_key(module), "src/run/{module}.rs not read");
    }
    let loop_edges = [
        "runner -> main_loop",
        "main_loop -> state",
        "main_loop -> checkpoint",
        "main_loop -> observe",
        "state -> tally",
    ];
    for edge in loop_edges {
        assert!(
            edges.iter().any(|e| e == edge),
            "{edge} not found in\n{edges:#?}"
        );
    }
    assert!(edges.len() >= 15, "only {} imports found", edges.len());
    if let Some(c) = cycle(&graph) {
        panic!("src/run/ imports in a cycle: {}", c.join(" -> "));
    }
}

/// The reading sees every way a file can name another, and [`cycle`] finds what it
/// should, on sources made up for it.
#[test]
fn the_import_reading_sees_every_form() {
    let lib = "pub mod run;\npub use run::a::{Thing, other as renamed};\npub use run::b as bee;\n";
    let files = BTreeMap::from([
        ("a".to_string(), "use crate::run::{b::X, c};\n".to_string()),
        ("b".to_string(), "fn f() { super::c::g(); }\n".to_string()),
        ("c".to_string(), "use crate::{Error, Thing};\n".to_string()),
        (
            "d".to_string(),
            "/// [`crate::run::a`]\n// crate::run::b\nconst S: &str = \"crate::run::c\";\nfn f<'a>(c: char) -> bool { c == '\"' && crate::bee::h() }\n"
                .to_string(),
        ),
    ]);
    let graph = graph(&files, lib);
    let expect = |to: &[&str]| to.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>();
    assert_eq!(graph["a"], expect(&["b", "c"]));
    assert_eq!(graph["b"], expect(&["c"]));
    assert_eq!(graph["c"], expect(&["a"]));
    assert_eq!(
        graph["d"],
        expect(&["b"]),
        "comments and strings are not imports"
    );
    let c = cycle(&graph).expect("a -> b -> c -> a");
    assert_eq!(c.first(), c.last());
    assert_eq!(c.len(), 4, "{c:?}");
    let mut acyclic = graph.clone();
    acyclic.insert("c".to_string(), BTreeSet::new());
    assert_eq!(cycle(&acyclic), None);
}
