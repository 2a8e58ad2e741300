//! Readers of foreign scene formats: SURFER's `.jsurf` ([`jsurf`]) and surf's `.pic` scripts
//! ([`pic`]). Each translates a file into kardia's own scene text (a [`Translation`]), so
//! `kardia convert` writes exactly what `kardia render` and `kardia explore` read, and nothing
//! of these formats reaches the renderer. [`load`] reads a path of any supported kind.

pub mod jsurf;
pub mod pic;

use std::path::Path;

use crate::scene::{self, Animation, LoadOptions, Scene, SceneError};

/// The kinds of file kardia reads, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// kardia's own scene text (any extension other than the ones below).
    Scene,
    /// SURFER's `.jsurf` (Java properties).
    Jsurf,
    /// surf's `.pic` script.
    Pic,
}

impl Format {
    /// The format of `path`, by its extension (any case): `.jsurf`, `.pic`, else a scene.
    pub fn of_path(path: &Path) -> Format {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("jsurf") => Format::Jsurf,
            Some("pic") => Format::Pic,
            _ => Format::Scene,
        }
    }
}

/// A problem in a foreign file that does not stop it being read: a key kardia ignores, or one
/// it renders differently. `line` is 1-based in the source file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Warning {
    /// The source file's line (1-based).
    pub line: usize,
    /// What kardia does with it, naming the key.
    pub message: String,
}

/// A foreign file translated into kardia's scene text.
#[derive(Debug, Clone, PartialEq)]
pub struct Translation {
    /// The scene text (ends with a newline).
    pub text: String,
    /// For each line of `text` (index 0 = line 1), the line of the source file it comes from
    /// (1-based; 0 for a line of no one source line, such as the header).
    pub source_lines: Vec<usize>,
    /// Keys ignored or rendered differently, in the order of the file.
    pub warnings: Vec<Warning>,
}

/// What [`load`] read: the scene, its text (translated when the file is foreign), what it
/// says of its animation and the reader's warnings.
#[derive(Debug)]
pub struct Loaded {
    /// The scene as a still (frame 0 of 1), ready to render.
    pub scene: Scene,
    /// Its `FRAMES`, `FPS` and whether anything depends on the time (the translated text's,
    /// for a foreign file).
    pub animation: Animation,
    /// kardia's scene text for it (the file itself for a scene file).
    pub text: String,
    /// The reader's warnings (none for a scene file).
    pub warnings: Vec<Warning>,
}

/// Translates `text`, a file of `format` named `file` (for messages), into kardia's scene
/// text; a scene file comes back unchanged. A malformed file is an error at its line.
pub fn translate(format: Format, text: &str, file: &str) -> Result<Translation, SceneError> {
    match format {
        Format::Scene => Ok(Translation {
            text: text.to_string(),
            source_lines: (1..=text.lines().count()).collect(),
            warnings: Vec::new(),
        }),
        Format::Jsurf => jsurf::translate(text, file),
        Format::Pic => pic::translate(text, file),
    }
}

/// Reads the file at `path` of any supported kind (by [`Format::of_path`]) into a scene (read
/// as a still, whatever `options.time` says). An error in the translated scene (an equation
/// kardia cannot read, say) is reported at the source file's line it came from, with the
/// translated line quoted. Whatever reads the scene again (at other frames) must read
/// [`Loaded::text`], never the file: a foreign file is not scene text.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let source = std::fs::read_to_string(path).map_err(|e| SceneError::Unreadable {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    let name = path.display().to_string();
    let format = Format::of_path(path);
    let still = LoadOptions {
        time: None,
        ..*options
    };
    if format == Format::Scene {
        let (scene, animation) = scene::parse_animated(&source, &name, &still)?;
        return Ok(Loaded {
            scene,
            animation,
            text: source,
            warnings: Vec::new(),
        });
    }
    let translation = translate(format, &source, &name)?;
    let (scene, animation) = scene::parse_animated(&translation.text, &name, &still)
        .map_err(|e| at_source_line(e, &translation, &source, &name))?;
    Ok(Loaded {
        scene,
        animation,
        text: translation.text,
        warnings: translation.warnings,
    })
}

/// Parses a translation, mapping an error back to the source file's line.
pub fn parse_translation(
    translation: &Translation,
    source: &str,
    file: &str,
    options: &LoadOptions,
) -> Result<Scene, SceneError> {
    scene::parse(&translation.text, file, options)
        .map_err(|e| at_source_line(e, translation, source, file))
}

/// An error in a translation's scene text as an error at the source file's line it came from.
fn at_source_line(
    e: SceneError,
    translation: &Translation,
    source: &str,
    file: &str,
) -> SceneError {
    let Some((line, _)) = e.location() else {
        return e;
    };
    let generated = translation.text.lines().nth(line - 1).unwrap_or("");
    let source_line = translation.source_lines.get(line - 1).copied().unwrap_or(0);
    let message = format!(
        "{} (in the kardia scene line it became: {generated})",
        e.message()
    );
    at_line(source, file, source_line.max(1), message, "here")
}

/// An error spanning line `line` (1-based) of `source`.
pub(crate) fn at_line(
    source: &str,
    file: &str,
    line: usize,
    message: impl Into<String>,
    label: &str,
) -> SceneError {
    let (start, end) = line_range(source, line);
    SceneError::at(source, file, start..end, message, label, None)
}

/// The byte range of line `line` (1-based) of `text`, without its line break.
pub(crate) fn line_range(text: &str, line: usize) -> (usize, usize) {
    let mut start = 0;
    for (i, l) in text.split('\n').enumerate() {
        let end = start + l.len();
        if i + 1 == line {
            return (start, end - usize::from(l.ends_with('\r')));
        }
        start = end + 1;
    }
    (text.len(), text.len())
}

/// Scene text being written line by line, each line with the source line it comes from.
#[derive(Debug, Default)]
pub(crate) struct SceneText {
    lines: Vec<(String, usize)>,
}

impl SceneText {
    /// Adds `line` (no line break), from source line `from` (0: none).
    pub(crate) fn push(&mut self, line: impl Into<String>, from: usize) {
        self.lines.push((line.into(), from));
    }

    /// The finished translation.
    pub(crate) fn finish(self, warnings: Vec<Warning>) -> Translation {
        let mut text = String::new();
        let mut source_lines = Vec::with_capacity(self.lines.len());
        for (line, from) in self.lines {
            text.push_str(&line);
            text.push('\n');
            source_lines.push(from);
        }
        Translation {
            text,
            source_lines,
            warnings,
        }
    }
}

/// A number as the scene language reads it back exactly (Rust's shortest round trip).
pub(crate) fn num(x: f64) -> String {
    let x = if x == 0.0 { 0.0 } else { x };
    format!("{x}")
}

/// A vector as `(x, y, z)`.
pub(crate) fn vector(v: [f64; 3]) -> String {
    format!("({}, {}, {})", num(v[0]), num(v[1]), num(v[2]))
}

/// An sRGB-encoded colour component in [0, 1] as kardia's linear value (the foreign programs
/// shade in sRGB values; kardia shades in linear light and encodes at the end).
pub(crate) fn srgb_to_linear(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// An sRGB colour as a linear one.
pub(crate) fn linear(c: [f64; 3]) -> [f64; 3] {
    c.map(srgb_to_linear)
}

/// `m · v` for a 3×3 matrix given by rows.
pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// `a · b` for 3×3 matrices given by rows.
pub(crate) fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The transpose of a 3×3 matrix.
pub(crate) fn transpose(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_follow_the_extension_in_any_case() {
        assert_eq!(Format::of_path(Path::new("a/b.jsurf")), Format::Jsurf);
        assert_eq!(Format::of_path(Path::new("B.PIC")), Format::Pic);
        assert_eq!(Format::of_path(Path::new("c.scene")), Format::Scene);
        assert_eq!(Format::of_path(Path::new("noext")), Format::Scene);
    }

    #[test]
    fn line_ranges_exclude_the_line_break() {
        let text = "ab\r\ncde\n\nf";
        assert_eq!(line_range(text, 1), (0, 2));
        assert_eq!(line_range(text, 2), (4, 7));
        assert_eq!(line_range(text, 3), (8, 8));
        assert_eq!(line_range(text, 4), (9, 10));
    }

    #[test]
    fn srgb_white_and_black_stay_and_the_middle_darkens() {
        assert_eq!(srgb_to_linear(1.0), 1.0);
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
    }
}
