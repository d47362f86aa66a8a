//! `docs/recipe.md`, the reference of every recipe key, is generated from the documented
//! fields of the recipe's structs (`plenoptic_scene::recipe`) and the presets' values, and this
//! test fails when the committed file differs from what the sources say.
//!
//! Regenerate it with `PLENOPTIC_BLESS=1 cargo test --test recipe_reference`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plenoptic_scene::recipe::Preset;
use syn::{Fields, Item, ItemStruct};

/// The recipe's tables, in the order a recipe is written: heading, struct, source file.
const TABLES: [(&str, &str, &str); 7] = [
    ("top level", "Recipe", "mod.rs"),
    ("`[[scene]]`", "SceneEntry", "mod.rs"),
    ("`[view_space]`", "ViewSpaceToml", "mod.rs"),
    ("`[time]`", "TimeToml", "mod.rs"),
    ("`[sun]`", "SunToml", "daylight.rs"),
    ("`[sky]`", "SkyToml", "daylight.rs"),
    ("`[[light_group]]`", "LightGroupToml", "groups.rs"),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn recipe_source(file: &str) -> syn::File {
    let path = root().join("crates/plenoptic_scene/src/recipe").join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    syn::parse_file(&text).unwrap_or_else(|e| panic!("{path:?}: {e}"))
}

fn find_struct<'a>(file: &'a syn::File, name: &str) -> &'a ItemStruct {
    file.items
        .iter()
        .find_map(|item| match item {
            Item::Struct(s) if s.ident == name => Some(s),
            _ => None,
        })
        .unwrap_or_else(|| panic!("struct {name} not found"))
}

/// The doc comment of an item as one line: paragraphs joined, intra-doc links unwrapped,
/// table pipes escaped.
fn doc(attrs: &[syn::Attribute]) -> String {
    let lines: Vec<String> = attrs
        .iter()
        .filter(|a| a.path().is_ident("doc"))
        .filter_map(|a| match &a.meta {
            syn::Meta::NameValue(nv) => match &nv.value {
                syn::Expr::Lit(syn::ExprLit {
                    lit: syn::Lit::Str(s),
                    ..
                }) => Some(s.value().trim().to_owned()),
                _ => None,
            },
            _ => None,
        })
        .collect();
    lines
        .join(" ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace("[`", "`")
        .replace("`]", "`")
        .replace('|', "\\|")
}

/// `(key, doc)` of every field of a struct; the recipe's own tables are left out of the top
/// level, which has a section for each.
fn keys(s: &ItemStruct) -> Vec<(String, String)> {
    let Fields::Named(fields) = &s.fields else {
        panic!("{} has no named fields", s.ident)
    };
    let tables = [
        "scene",
        "view_space",
        "time",
        "quality",
        "sun",
        "sky",
        "light_group",
    ];
    fields
        .named
        .iter()
        .map(|f| (f.ident.as_ref().unwrap().to_string(), doc(&f.attrs)))
        .filter(|(k, _)| s.ident != "Recipe" || !tables.contains(&k.as_str()))
        .collect()
}

/// A preset's value as a recipe writes it (`f32` fields at their own precision).
fn value(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => (*f as f32).to_string(),
        other => other.to_string(),
    }
}

fn quality_section(md: &mut String) {
    let quality = recipe_source("quality.rs");
    let fields = keys(find_struct(&quality, "Quality"));
    let presets: Vec<toml::Table> = Preset::ALL
        .iter()
        .map(|p| toml::Table::try_from(p.quality()).expect("Quality serialises"))
        .collect();
    md.push_str("## `[quality]`\n\n");
    let _ = writeln!(
        md,
        "`preset` picks the starting values: {}. Every other key overrides one value of the \
         preset. The columns are the presets' values.\n",
        Preset::ALL
            .iter()
            .map(|p| format!("`{}`", p.name()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    md.push_str("| key |");
    for p in Preset::ALL {
        let _ = write!(md, " {} |", p.name());
    }
    md.push_str(" what it buys and what it costs |\n|---|");
    md.push_str(&"---|".repeat(Preset::ALL.len() + 1));
    md.push('\n');
    for (key, text) in fields {
        let _ = write!(md, "| `{key}` |");
        for values in &presets {
            let value_of = values
                .get(&key)
                .unwrap_or_else(|| panic!("preset without {key}"));
            let _ = write!(md, " {} |", value(value_of));
        }
        let _ = writeln!(md, " {text} |");
    }
    md.push('\n');
}

fn table_section(md: &mut String, heading: &str, name: &str, file: &str) {
    let source = recipe_source(file);
    let s = find_struct(&source, name);
    let _ = writeln!(
        md,
        "## {heading}\n\n{}\n",
        doc(&s.attrs).replace("\\|", "|")
    );
    md.push_str("| key | meaning |\n|---|---|\n");
    for (key, text) in keys(s) {
        let _ = writeln!(md, "| `{key}` | {text} |");
    }
    md.push('\n');
}

fn reference() -> String {
    let mut md = String::from(
        "# Recipe reference\n\n\
         A bake recipe is a TOML file beside the glTF scene; `plenoptic bake RECIPE` bakes it \
         and `plenoptic plan RECIPE` prints the plan and its estimated cost first. Unknown keys \
         are refused with an error that names them.\n\n\
         This page is generated from the documented fields of `plenoptic_scene::recipe` \
         (`PLENOPTIC_BLESS=1 cargo test --test recipe_reference`).\n\n",
    );
    for (i, (heading, name, file)) in TABLES.iter().enumerate() {
        table_section(&mut md, heading, name, file);
        if i == 3 {
            quality_section(&mut md);
        }
    }
    md
}

#[test]
fn recipe_reference_is_current() {
    let path = root().join("docs/recipe.md");
    let generated = reference();
    if std::env::var_os("PLENOPTIC_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is out of date: run `PLENOPTIC_BLESS=1 cargo test --test recipe_reference`",
        Path::new("docs/recipe.md").display()
    );
}

#[test]
fn every_quality_key_is_documented_and_overridable() {
    let quality = recipe_source("quality.rs");
    let overrides = keys(find_struct(&recipe_source("mod.rs"), "QualityToml"));
    for (key, text) in keys(find_struct(&quality, "Quality")) {
        assert!(!text.is_empty(), "Quality::{key} has no doc comment");
        assert!(
            overrides.iter().any(|(k, _)| *k == key),
            "Quality::{key} cannot be overridden in [quality]"
        );
    }
}
