//! The recipe's `[[light_group]]` tables: named groups of emitters whose light a bake stores
//! apart, so that a runtime can scale each group ([`crate::groups`]).
//!
//! ```toml
//! [[light_group]]
//! name = "lamp"
//! emitters = ["DeskLamp", "LampShade"]   # glTF lights, emissive materials or objects
//!
//! [[light_group]]
//! name = "daylight"
//! emitters = ["sun", "sky"]
//! ```

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::ErrFn;
use crate::error::RecipeError;

/// The `[[light_group]]` table: a named group of emitters whose light the pack stores apart,
/// so that the runtime scales it by a colour × intensity (lamps on and off, the daylight
/// dimmed). Every emitter belongs to one group; emitters no group names form a default group.
/// Its cost in the bake: a rendering of every range image, ambient field and volume sample
/// per group; in the pack, one lighting layer per group but one (the tour's three groups: 2.17×
/// the bake time, 1.59× the pack).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightGroupToml {
    /// The group's name, which the runtime and `plenoptic render --light NAME=I` use.
    pub name: Spanned<String>,
    /// Its emitters: `"sun"`, `"sky"`, glTF lights by name, emissive materials by name (every
    /// object using one), or emissive objects by their node's name.
    #[serde(default)]
    pub emitters: Vec<Spanned<String>>,
}

/// A validated light group, with the recipe lines of its name and emitters when the recipe
/// was parsed from text.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LightGroupSpec {
    /// The group's name.
    pub name: String,
    /// The line of its name in the recipe.
    pub line: Option<usize>,
    /// The emitters it names.
    pub emitters: Vec<EmitterRef>,
}

/// An emitter named in a light group.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EmitterRef {
    /// The name as written.
    pub name: String,
    /// Its line in the recipe.
    pub line: Option<usize>,
}

/// The 1-based line of byte offset `at` in `text`.
fn line_of(text: Option<&str>, at: usize) -> Option<usize> {
    let text = text?;
    Some(text.get(..at.min(text.len()))?.matches('\n').count() + 1)
}

/// Checks the tables (a name each, at most [`MAX_GROUPS`] groups) into specs, lines taken
/// from `text` when the recipe was parsed from it.
pub(super) fn validate(
    tables: &[LightGroupToml],
    text: Option<&str>,
    err: &ErrFn,
) -> Result<Vec<LightGroupSpec>, RecipeError> {
    if tables.len() > MAX_GROUPS {
        return Err(err(
            "light_group",
            &format!("at most {MAX_GROUPS} groups (each costs a rendering of the whole bake)"),
        ));
    }
    let mut out: Vec<LightGroupSpec> = Vec::with_capacity(tables.len());
    for (i, t) in tables.iter().enumerate() {
        let name = t.name.get_ref().trim().to_owned();
        if name.is_empty() || out.iter().any(|g| g.name == name) {
            return Err(err(
                &format!("light_group[{i}].name"),
                &format!("'{name}' must be a name no other group has"),
            ));
        }
        out.push(LightGroupSpec {
            name,
            line: line_of(text, t.name.span().start),
            emitters: t
                .emitters
                .iter()
                .map(|e| EmitterRef {
                    name: e.get_ref().clone(),
                    line: line_of(text, e.span().start),
                })
                .collect(),
        });
    }
    Ok(out)
}

/// Most light groups a recipe may declare.
pub const MAX_GROUPS: usize = 16;
