//! Errors of import, scene building and recipe validation.
//!
//! Every error names where it comes from: the file (or `<builder>` / `<memory>` for data that
//! never touched the disk), the element inside it (`accessor 3`, `node 'Door'`, a recipe key)
//! and the problem, so that a message such as
//! `scene.gltf: accessor 3: index 812 out of range for 24 vertices` can be acted on without a
//! debugger.

use std::path::PathBuf;

/// Result of scene import and building.
pub type Result<T, E = SceneError> = std::result::Result<T, E>;

/// An error of glTF import or of the scene builder.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file itself could not be read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not glTF: bad GLB container or JSON that does not deserialise.
    #[error("{file}: {message}")]
    Parse {
        /// The file name.
        file: String,
        /// What the parser said (with line and column for JSON).
        message: String,
    },
    /// The glTF is well-formed JSON but one of its elements is invalid or unsupported.
    #[error("{file}: {element}: {problem}")]
    Invalid {
        /// The file name.
        file: String,
        /// The element, e.g. `accessor 3`, `buffer 0`, `node 'Door'`, `scene`.
        element: String,
        /// What is wrong with it.
        problem: String,
    },
    /// An external resource (buffer or image) named by the file could not be read.
    #[error("{file}: {element}: cannot read {}: {source}", path.display())]
    Resource {
        /// The glTF file name.
        file: String,
        /// The element that names the resource, e.g. `buffer 0`.
        element: String,
        /// The resolved path of the resource.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl SceneError {
    /// An [`SceneError::Invalid`] for `file`, `element` and `problem`.
    pub fn invalid(
        file: impl Into<String>,
        element: impl Into<String>,
        problem: impl Into<String>,
    ) -> Self {
        Self::Invalid {
            file: file.into(),
            element: element.into(),
            problem: problem.into(),
        }
    }
}

/// An error of reading or validating a bake recipe.
#[derive(Debug, thiserror::Error)]
pub enum RecipeError {
    /// The recipe file could not be read.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The TOML does not parse or does not match the recipe's shape (unknown key, wrong type).
    #[error("{file}: {message}")]
    Parse {
        /// The recipe's name.
        file: String,
        /// The parser's message, with line, column and key.
        message: String,
    },
    /// A value parses but is not acceptable.
    #[error("{file}: {key}: {problem}")]
    Invalid {
        /// The recipe's name.
        file: String,
        /// The dotted key, e.g. `view_space.max` or `scene[1].rotation`.
        key: String,
        /// What is wrong with it.
        problem: String,
    },
}
