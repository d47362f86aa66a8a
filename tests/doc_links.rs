//! Every file the documentation points at exists in the repository.
//!
//! Read: the Markdown files (`README.md`, `docs/`, `examples/`, `crates/`), and the comments
//! (`//`, `///`, `//!`) of the `.rs` and `.wgsl` files under `crates/`, `examples/`, `tests/`,
//! `benches/` and `src/`. Checked there:
//!
//! - Markdown links and images, `[text](path)`, `![alt](path)` and `[label]: path`, and
//!   `src="path"` in Markdown's HTML: in a Markdown file the path is taken relative to the file,
//!   as a reader's viewer resolves it; in a comment relative to the source file or to the
//!   repository root. Web links (`scheme://`, `mailto:`) and anchors within the page (`#…`)
//!   are skipped; an anchor after a path is dropped.
//! - Mentions, backticked or bare, of a Markdown file (`docs/pack-format.md`,
//!   `bake-accuracy.md`) and of a source or shader file with a directory
//!   (`plenoptic_recon/src/shadow.rs`, `reconstruct/geometry/rays.wgsl`): such a mention
//!   names a file of the tree if a file's path ends with it, component by component. A
//!   mention whose first folder is a dependency (a package in `Cargo.lock` that is not one of
//!   `crates/`, as in `bevy_image/src/ktx2.rs`) names a file of that package and is skipped.
//!
//! The test fails with the list of every broken link and mention, each with its file and line.
//! Run it alone with `cargo test --test doc_links`.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// Folders never read, and never targets of a mention: build output and version control.
const SKIPPED_DIRS: [&str; 3] = ["target", ".git", "node_modules"];

/// Where the comments of source files are read.
const SOURCE_ROOTS: [&str; 5] = ["crates", "examples", "tests", "benches", "src"];

/// Extensions of the files whose mentions are checked when the mention has a directory.
const SOURCE_EXTENSIONS: [&str; 2] = ["rs", "wgsl"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir`, recursively, without the skipped folders.
fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let Ok(kind) = entry.file_type() else {
            continue;
        };
        if kind.is_dir() {
            if !SKIPPED_DIRS.contains(&name.as_ref()) {
                walk(&path, out);
            }
        } else if kind.is_file() {
            out.push(path);
        }
    }
}

fn extension(path: &str) -> Option<&str> {
    let name = path.rsplit('/').next()?;
    let (stem, ext) = name.rsplit_once('.')?;
    (!stem.is_empty()).then_some(ext)
}

/// What a text points at: the targets of its Markdown links, and its file mentions.
#[derive(Default)]
struct Targets {
    links: Vec<(usize, String)>,
    mentions: Vec<(usize, String)>,
}

/// Is `target` a web address, a mail address or an anchor in the same page?
fn is_external(target: &str) -> bool {
    target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:")
        || target.starts_with("data:")
}

/// The path of a link target: without its title, anchor, query and angle brackets.
fn link_path(target: &str) -> &str {
    let target = target.trim();
    let target = target.strip_prefix('<').unwrap_or(target);
    let target = target.split_whitespace().next().unwrap_or("");
    let target = target.trim_end_matches('>');
    let end = target.find(['#', '?']).unwrap_or(target.len());
    &target[..end]
}

/// Is `target`, from a Markdown link, a path (not an intra-doc link such as
/// `crate::module::Item` or `Self::method`)?
fn is_path_like(target: &str) -> bool {
    !target.contains("::") && (target.contains('/') || extension(target).is_some())
}

/// Markdown link targets in one line: `[text](target)` (images too), `[label]: target`,
/// `src="target"`.
fn links_in(line: &str, out: &mut Vec<String>) {
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        // The target ends at the parenthesis that closes the one after `]`.
        let mut depth = 1;
        let mut end = None;
        for (i, c) in after.char_indices() {
            match c {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        end = Some(i);
                        break;
                    }
                }
                _ => {}
            }
        }
        let Some(end) = end else { break };
        out.push(after[..end].to_string());
        rest = &after[end..];
    }
    let trimmed = line.trim_start();
    if let Some(label_end) = trimmed.strip_prefix('[').and_then(|t| t.find("]:")) {
        let target = trimmed[1 + label_end + 2..].trim();
        if !target.is_empty() {
            out.push(target.to_string());
        }
    }
    let mut rest = line;
    while let Some(at) = rest.find("src=\"") {
        let after = &rest[at + 5..];
        let Some(end) = after.find('"') else { break };
        out.push(after[..end].to_string());
        rest = &after[end..];
    }
}

/// `line` without the targets of its Markdown links, which are checked as links.
fn without_link_targets(line: &str) -> String {
    let mut kept = String::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        kept.push_str(&rest[..at + 1]);
        let after = &rest[at + 2..];
        rest = after.find(')').map_or("", |end| &after[end + 1..]);
    }
    kept.push_str(rest);
    let trimmed = kept.trim_start();
    if trimmed.starts_with('[') && trimmed.contains("]:") {
        return String::new();
    }
    kept
}

/// Mentions of files in one line: words that end in `.md`, or in a source extension and
/// have a directory.
fn mentions_in(line: &str, out: &mut Vec<String>) {
    let line = without_link_targets(line);
    let is_separator = |c: char| {
        c.is_whitespace()
            || matches!(c, '`' | '(' | ')' | '[' | ']' | '<' | '>' | '"' | '\'')
            || matches!(c, ',' | ';' | '*' | '|' | '{' | '}' | '=')
    };
    for word in line.split(is_separator) {
        if word.contains("://") || word.starts_with("//") {
            continue;
        }
        // A line number or an anchor after a file name (`:12`, `#L3`) is not part of it.
        let word = word.split([':', '#']).next().unwrap_or("");
        let word = word.trim_end_matches(['.', '!', '?']);
        let word = word.strip_prefix("./").unwrap_or(word);
        let Some(ext) = extension(word) else { continue };
        let named = ext == "md" || (SOURCE_EXTENSIONS.contains(&ext) && word.contains('/'));
        // A pattern (`docs/**`) or a placeholder in capitals names no single file.
        let concrete = !word.contains("**") && word.chars().any(|c| c.is_ascii_lowercase());
        if named && concrete {
            out.push(word.to_string());
        }
    }
}

/// The comment of a line of Rust or WGSL: after `//` at the line's start, or after code
/// when no string literal could hold the `//`.
fn comment_of(line: &str) -> Option<&str> {
    let trimmed = line.trim_start();
    if let Some(comment) = trimmed.strip_prefix("//") {
        return Some(comment);
    }
    let at = line.find("//")?;
    let code = &line[..at];
    (!code.contains('"') && !code.ends_with(':')).then(|| &line[at + 2..])
}

fn targets_of_markdown(text: &str) -> Targets {
    let mut targets = Targets::default();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let mut links = Vec::new();
        links_in(line, &mut links);
        targets.links.extend(links.into_iter().map(|l| (i + 1, l)));
        // Code blocks hold commands, whose file arguments may be outputs; links are checked
        // everywhere, mentions only in prose.
        if !fenced {
            let mut mentions = Vec::new();
            mentions_in(line, &mut mentions);
            targets
                .mentions
                .extend(mentions.into_iter().map(|m| (i + 1, m)));
        }
    }
    targets
}

fn targets_of_source(text: &str) -> Targets {
    let mut targets = Targets::default();
    for (i, line) in text.lines().enumerate() {
        let Some(comment) = comment_of(line) else {
            continue;
        };
        let mut links = Vec::new();
        links_in(comment, &mut links);
        targets.links.extend(links.into_iter().map(|l| (i + 1, l)));
        let mut mentions = Vec::new();
        mentions_in(comment, &mut mentions);
        targets
            .mentions
            .extend(mentions.into_iter().map(|m| (i + 1, m)));
    }
    targets
}

/// `base/relative` with `.` and `..` resolved lexically; `None` if it climbs out of the
/// repository.
fn join(base: &str, relative: &str) -> Option<String> {
    let mut parts: Vec<&str> = if relative.starts_with('/') {
        Vec::new()
    } else {
        base.split('/').filter(|p| !p.is_empty()).collect()
    };
    for part in relative.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                parts.pop()?;
            }
            part => parts.push(part),
        }
    }
    Some(parts.join("/"))
}

/// The repository's files and folders, as paths relative to its root with `/`.
struct Tree {
    files: BTreeSet<String>,
    dirs: BTreeSet<String>,
    /// Packages in `Cargo.lock` that are not workspace crates, with `-` as `_`.
    dependencies: BTreeSet<String>,
}

impl Tree {
    fn new(root: &Path, files: &[PathBuf]) -> Tree {
        let mut tree = Tree {
            files: BTreeSet::new(),
            dirs: BTreeSet::new(),
            dependencies: BTreeSet::new(),
        };
        tree.dirs.insert(String::new());
        for file in files {
            let relative = relative(root, file);
            let mut dir = relative.as_str();
            while let Some((parent, _)) = dir.rsplit_once('/') {
                tree.dirs.insert(parent.to_string());
                dir = parent;
            }
            tree.files.insert(relative);
        }
        let lock = fs::read_to_string(root.join("Cargo.lock")).unwrap_or_default();
        for line in lock.lines() {
            if let Some(name) = line.strip_prefix("name = ") {
                let name = name.trim_matches('"').replace('-', "_");
                if !tree.dirs.contains(&format!("crates/{name}")) {
                    tree.dependencies.insert(name);
                }
            }
        }
        tree
    }

    /// Does `mention` name a file in a dependency's sources?
    fn in_dependency(&self, mention: &str) -> bool {
        mention
            .split_once('/')
            .is_some_and(|(first, _)| self.dependencies.contains(&first.replace('-', "_")))
    }

    fn exists(&self, path: &str) -> bool {
        let path = path.trim_end_matches('/');
        self.files.contains(path) || self.dirs.contains(path)
    }

    /// Does some file's path end with `mention`, component by component?
    fn ends_with(&self, mention: &str) -> bool {
        let suffix = format!("/{mention}");
        self.files
            .iter()
            .any(|file| file == mention || file.ends_with(&suffix))
    }
}

fn relative(root: &Path, path: &Path) -> String {
    let relative = path.strip_prefix(root).unwrap_or(path);
    let parts: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

/// The broken links and mentions of one file, as `file:line: what`.
fn broken(tree: &Tree, file: &str, targets: &Targets, markdown: bool) -> Vec<String> {
    let dir = file.rsplit_once('/').map_or("", |(dir, _)| dir);
    let mut broken: Vec<String> = Vec::new();
    for (line, target) in &targets.links {
        if is_external(target.trim()) {
            continue;
        }
        let path = link_path(target);
        if path.is_empty() || (!markdown && !is_path_like(path)) {
            continue;
        }
        let from_file = join(dir, path).is_some_and(|p| tree.exists(&p));
        // A comment's link has no page to be relative to: the source file's folder or the
        // repository root.
        let from_root = !markdown && join("", path).is_some_and(|p| tree.exists(&p));
        if !from_file && !from_root {
            broken.push(format!("{file}:{line}: missing {path}"));
        }
    }
    for (line, mention) in &targets.mentions {
        let from_file = join(dir, mention).is_some_and(|p| tree.exists(&p));
        if !from_file && !tree.ends_with(mention) && !tree.in_dependency(mention) {
            let problem = format!("{file}:{line}: missing {mention}");
            // A link whose text names its own target is reported once.
            if !broken.contains(&problem) {
                broken.push(problem);
            }
        }
    }
    broken
}

#[test]
fn documentation_points_at_files_that_exist() {
    let root = root();
    let mut files = Vec::new();
    walk(&root, &mut files);
    let tree = Tree::new(&root, &files);

    let mut read = 0;
    let mut problems = Vec::new();
    for file in &files {
        let path = relative(&root, file);
        let Some(ext) = extension(&path) else {
            continue;
        };
        let markdown = ext == "md";
        let in_sources = SOURCE_ROOTS
            .iter()
            .any(|dir| path.starts_with(&format!("{dir}/")));
        let documented =
            markdown && (!path.contains('/') || path.starts_with("docs/") || in_sources);
        let source = in_sources && SOURCE_EXTENSIONS.contains(&ext);
        if !documented && !source {
            continue;
        }
        let Ok(text) = fs::read_to_string(file) else {
            continue;
        };
        read += 1;
        let targets = if markdown {
            targets_of_markdown(&text)
        } else {
            targets_of_source(&text)
        };
        problems.extend(broken(&tree, &path, &targets, markdown));
    }
    assert!(read > 10, "read only {read} files under {}", root.display());
    assert!(
        problems.is_empty(),
        "{} links or mentions of files that are not in the repository:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn finds_links_and_mentions() {
    let text = "See [the format](pack-format.md#header), ![plot](results/plot.svg),\n\
                `design.md`, crates/x/README.md: and [web](https://example.invalid/a.md).\n\
                ```\n\
                cargo run -- --out out.md [ok](fenced.md)\n\
                ```\n";
    let targets = targets_of_markdown(text);
    let links: Vec<&str> = targets.links.iter().map(|(_, l)| link_path(l)).collect();
    assert_eq!(
        links,
        [
            "pack-format.md",
            "results/plot.svg",
            "https://example.invalid/a.md",
            "fenced.md"
        ]
    );
    let mentions: Vec<&str> = targets.mentions.iter().map(|(_, m)| m.as_str()).collect();
    assert_eq!(mentions, ["design.md", "crates/x/README.md"]);

    let source = "let x = 1; // see plan/ambient.rs and [`Item`](crate::Item)\n\
                  let s = \"a // b.md\";\n";
    let targets = targets_of_source(source);
    let mentions: Vec<&str> = targets.mentions.iter().map(|(_, m)| m.as_str()).collect();
    assert_eq!(mentions, ["plan/ambient.rs"]);
    assert!(!is_path_like(link_path(&targets.links[0].1)));
}

#[test]
fn a_missing_file_is_reported() {
    let files = [
        PathBuf::from("/r/docs/a.md"),
        PathBuf::from("/r/crates/c/src/lib.rs"),
    ];
    let tree = Tree::new(Path::new("/r"), &files);
    let targets = targets_of_markdown(
        "[a](a.md) [b](b.md) `c/src/lib.rs` `design.md` [up](../crates/c/src/lib.rs)\n",
    );
    let broken = broken(&tree, "docs/a.md", &targets, true);
    assert_eq!(
        broken,
        [
            "docs/a.md:1: missing b.md",
            "docs/a.md:1: missing design.md"
        ]
    );
}
