//! The scene-file parser.

use super::{LoadOptions, Scene, SceneError};

/// Parses scene text; `name` is used in error messages (usually the file path).
pub fn parse(text: &str, name: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
    let _ = (text, name, options);
    todo!("scene parser")
}

/// Reads and parses a scene file.
pub fn parse_file(path: &std::path::Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Unreadable {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    parse(&text, &path.display().to_string(), options)
}
