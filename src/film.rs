//! The film (a linear-RGB pixel buffer) and writing it to PNG or OpenEXR.

use crate::geometry::DVec3;
use std::path::Path;

/// A rendered image: `width × height` linear-RGB pixels, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, `width·height` of them, row-major from the top-left.
    pub pixels: Vec<DVec3>,
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The extension is not .png or .exr.
    #[error("cannot tell the image format of {0}: use a .png or .exr file name")]
    UnknownFormat(String),
    /// The directory to write into does not exist or is not a directory.
    #[error("the output directory {0} does not exist")]
    NoDirectory(String),
    /// Writing failed.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// Target path.
        path: String,
        /// Why.
        reason: String,
    },
}

/// Checks, before any rendering, that `path` can be written: known extension, existing
/// directory.
pub fn check_output_path(path: &Path) -> Result<(), OutputError> {
    let _ = path;
    Ok(()) // TODO: renderer work
}

/// Writes the image atomically (temporary file beside the target, then rename): PNG as 8-bit
/// sRGB, EXR as linear float, chosen by extension.
pub fn write_image(image: &Image, path: &Path) -> Result<(), OutputError> {
    let _ = (image, path);
    todo!("renderer work")
}
