//! The plugin's modules are layered one way (`docs/architecture.md`, "The plugin's layers"):
//! each layer imports only the layers below it, the features (geometry, image with volume
//! mode, background, cpu) never import each other, and `lit/` comes last. Features are ordered
//! by system sets, never by naming another feature's systems.
//!
//! This test reads the plugin's sources (Rust and WGSL), resolves every `crate::`, `super::`,
//! `self::` and child-module path and every shader `#import plenoptic::…` to the unit it names,
//! and fails on an import that goes sideways or up. It also holds every source file to at most
//! 600 lines. Standard library only: it never builds Bevy.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The units and their layers, lowest first. A module belongs to the unit with the longest
/// matching prefix; `lib.rs` (the plugin's assembly) is the top and may import anything.
const UNITS: &[(&str, u32)] = &[
    ("settings", 0),
    ("asset", 0),
    ("camera", 1),
    ("streaming", 2),
    ("proxy", 2),
    ("reconstruct", 3),
    ("reconstruct::geometry", 4),
    ("reconstruct::image", 4),
    ("reconstruct::background", 4),
    ("reconstruct::cpu", 4),
    ("lit", 5),
];

/// Longest source file allowed, in lines.
const MAX_LINES: usize = 600;

/// The unit (index into [`UNITS`]) a module path belongs to; `None` for the crate root.
fn unit_of(module: &[String]) -> Option<usize> {
    let joined = module.join("::");
    UNITS
        .iter()
        .enumerate()
        .filter(|(_, (prefix, _))| joined == *prefix || joined.starts_with(&format!("{prefix}::")))
        .max_by_key(|(_, (prefix, _))| prefix.len())
        .map(|(i, _)| i)
}

/// Whether a module in unit `from` may name something in unit `to`.
fn allowed(from: Option<usize>, to: Option<usize>) -> bool {
    match (from, to) {
        (None, _) => true,
        (Some(_), None) => false,
        (Some(f), Some(t)) => f == t || UNITS[t].1 < UNITS[f].1,
    }
}

/// The module path of a source file under `src/`.
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs").trim_end_matches(".wgsl");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_owned());
    }
    parts
}

/// Source text without comments (line and block) and string literals, so that paths in docs
/// and messages do not count.
fn strip(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for n in chars.by_ref() {
                    if n == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                let mut prev = ' ';
                for n in chars.by_ref() {
                    if prev == '*' && n == '/' {
                        break;
                    }
                    prev = n;
                }
            }
            '"' => {
                let mut escaped = false;
                for n in chars.by_ref() {
                    if n == '"' && !escaped {
                        break;
                    }
                    escaped = n == '\\' && !escaped;
                }
                out.push_str("\"\"");
            }
            _ => out.push(c),
        }
    }
    out
}

/// Expands a path tree starting at `s` (after a leading `root::`): `a::b`, `{a, b::{c, d}}`.
/// Returns the expanded paths (segments) and how many bytes were consumed.
fn expand(s: &str) -> (Vec<Vec<String>>, usize) {
    let bytes = s.as_bytes();
    let mut i = 0;
    let mut prefix = Vec::new();
    loop {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if i < bytes.len() && bytes[i] == b'{' {
            i += 1;
            let mut all = Vec::new();
            loop {
                let (paths, used) = expand(&s[i..]);
                i += used;
                for p in paths {
                    all.push(prefix.iter().cloned().chain(p).collect());
                }
                while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                    i += 1;
                }
                match bytes.get(i) {
                    Some(b',') => i += 1,
                    Some(b'}') => return (all, i + 1),
                    _ => return (all, i),
                }
                while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                    i += 1;
                }
                if bytes.get(i) == Some(&b'}') {
                    return (all, i + 1);
                }
            }
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
            i += 1;
        }
        if start == i {
            return (vec![prefix], i);
        }
        prefix.push(s[start..i].to_owned());
        if s[i..].starts_with("::") {
            i += 2;
        } else {
            return (vec![prefix], i);
        }
    }
}

/// Whether position `at` in `text` starts a path (not the tail of a longer identifier or path).
fn starts_path(text: &str, at: usize) -> bool {
    let before = text[..at].chars().next_back();
    !matches!(before, Some(c) if c.is_ascii_alphanumeric() || c == '_' || c == ':')
}

/// Every module path a Rust file names, resolved to absolute segments. A file's unit tests
/// (from its first `#[cfg(test)]` on) are left out: their `super::` is the file itself.
fn rust_paths(text: &str, module: &[String], children: &[String]) -> Vec<Vec<String>> {
    let text = strip(text);
    let text = text.split("#[cfg(test)]").next().unwrap_or_default();
    let mut found = Vec::new();
    let mut roots: Vec<String> = vec!["crate".into(), "super".into(), "self".into()];
    roots.extend(children.iter().cloned());
    for root in &roots {
        let needle = format!("{root}::");
        for (at, _) in text.match_indices(&needle) {
            if !starts_path(text, at) {
                continue;
            }
            let (paths, _) = expand(&text[at + needle.len()..]);
            for p in paths {
                let mut base: Vec<String> = match root.as_str() {
                    "crate" => Vec::new(),
                    "super" => module[..module.len().saturating_sub(1)].to_vec(),
                    "self" => module.to_vec(),
                    child => module.iter().cloned().chain([child.to_owned()]).collect(),
                };
                let mut rest = p.as_slice();
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
                base.extend(rest.iter().cloned());
                found.push(base);
            }
        }
    }
    found
}

/// Child modules declared by `mod name;` in a file.
fn declared_children(text: &str) -> Vec<String> {
    strip(text)
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            let l = l
                .strip_prefix("pub(crate) ")
                .or_else(|| l.strip_prefix("pub "))
                .unwrap_or(l);
            l.strip_prefix("mod ")?
                .strip_suffix(';')
                .map(|s| s.trim().to_owned())
        })
        .collect()
}

/// All `.rs` and `.wgsl` files under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("read src") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
            out.push(path);
        }
    }
}

/// The shader libraries: `#define_import_path plenoptic::name` → the defining file's module.
fn shader_libraries(files: &[(Vec<String>, PathBuf, String)]) -> HashMap<String, Vec<String>> {
    files
        .iter()
        .filter_map(|(module, _, text)| {
            let line = text
                .lines()
                .find_map(|l| l.trim().strip_prefix("#define_import_path "))?;
            Some((line.trim().to_owned(), module.clone()))
        })
        .collect()
}

/// Every plugin-internal shader library a WGSL file imports, as the library's module.
fn wgsl_paths(text: &str, libraries: &HashMap<String, Vec<String>>) -> Vec<Vec<String>> {
    strip(text)
        .lines()
        .filter_map(|l| l.trim().strip_prefix("#import "))
        .filter_map(|l| {
            let full: String = l
                .split("::{")
                .next()
                .unwrap_or(l)
                .split_whitespace()
                .next()?
                .to_owned();
            libraries
                .iter()
                .filter(|(lib, _)| full == **lib || full.starts_with(&format!("{lib}::")))
                .max_by_key(|(lib, _)| lib.len())
                .map(|(_, m)| m.clone())
        })
        .collect()
}

fn read_sources() -> Vec<(Vec<String>, PathBuf, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    sources(&src, &mut paths);
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(&src).expect("under src").to_path_buf();
            let text = fs::read_to_string(&p).expect("read source");
            (module_of(&rel), rel, text)
        })
        .collect()
}

/// Every import that goes sideways or up, as "file: path (unit → unit)".
fn violations(files: &[(Vec<String>, PathBuf, String)]) -> Vec<String> {
    let libraries = shader_libraries(files);
    let mut bad = Vec::new();
    for (module, rel, text) in files {
        let from = unit_of(module);
        let named = if rel.extension().is_some_and(|e| e == "wgsl") {
            wgsl_paths(text, &libraries)
        } else {
            rust_paths(text, module, &declared_children(text))
        };
        for path in named {
            // An item of the crate root (`crate::Foo`) belongs to the root; a module path to
            // its unit.
            let to = unit_of(&path);
            if !allowed(from, to) {
                let name = |u: Option<usize>| u.map_or("crate root", |u| UNITS[u].0);
                bad.push(format!(
                    "{}: {} ({} → {})",
                    rel.display(),
                    path.join("::"),
                    name(from),
                    name(to)
                ));
            }
        }
    }
    bad.sort();
    bad.dedup();
    bad
}

#[test]
fn imports_go_one_way() {
    let bad = violations(&read_sources());
    assert!(
        bad.is_empty(),
        "{} imports go sideways or up:\n{}",
        bad.len(),
        bad.join("\n")
    );
}

#[test]
fn no_source_file_over_600_lines() {
    let long: Vec<String> = read_sources()
        .iter()
        .filter(|(_, _, text)| text.lines().count() > MAX_LINES)
        .map(|(_, rel, text)| format!("{}: {} lines", rel.display(), text.lines().count()))
        .collect();
    assert!(
        long.is_empty(),
        "over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// The checker itself: a planted upward, sideways and root import are each caught; a downward
/// import, a child module and a path inside a comment or string are not.
#[test]
fn checker_catches_planted_imports() {
    let module = |s: &str| s.split("::").map(str::to_owned).collect::<Vec<_>>();
    let file = |m: &str, text: &str| {
        let rel = PathBuf::from(format!("{}.rs", m.replace("::", "/")));
        (module(m), rel, text.to_owned())
    };
    let files = vec![
        file(
            "camera",
            "use crate::lit::scene::X;\nuse crate::asset::Pack;",
        ),
        file(
            "reconstruct::geometry::frame",
            "use crate::{camera::C, reconstruct::{image::W, KeyTextures}};\n// crate::lit::x\nfn f() { let s = \"crate::cpu\"; super::super::cpu::run(); }",
        ),
        file("streaming", "use crate::PlenopticSettings;"),
        file(
            "reconstruct",
            "mod geometry;\nfn f() { geometry::volume::upload(); }",
        ),
        file(
            "lit::scene",
            "use crate::reconstruct::geometry::PlenopticMaterial;",
        ),
    ];
    let bad = violations(&files);
    assert_eq!(
        bad,
        vec![
            "camera.rs: lit::scene::X (camera → lit)".to_owned(),
            "reconstruct.rs: reconstruct::geometry::volume::upload (reconstruct → reconstruct::geometry)".to_owned(),
            "reconstruct/geometry/frame.rs: reconstruct::cpu::run (reconstruct::geometry → reconstruct::cpu)".to_owned(),
            "reconstruct/geometry/frame.rs: reconstruct::image::W (reconstruct::geometry → reconstruct::image)".to_owned(),
            "streaming.rs: PlenopticSettings (streaming → crate root)".to_owned(),
        ]
    );
}
