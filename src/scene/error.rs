//! Scene errors: where in the text, and what was expected.

use miette::{Diagnostic, NamedSource, SourceSpan};

/// A scene that could not be read or understood. Displays as one line
/// (`file:line:column: message`); as a [`miette::Diagnostic`] it also shows the source line
/// with a caret under the problem.
#[derive(Debug, thiserror::Error, Diagnostic)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file {path}: {reason}")]
    Unreadable {
        /// The path as given.
        path: String,
        /// The operating system's reason.
        reason: String,
    },
    /// The text is not a valid scene.
    #[error(transparent)]
    #[diagnostic(transparent)]
    Invalid(Box<InvalidScene>),
}

/// Where a scene text is wrong and what was expected there.
#[derive(Debug, thiserror::Error, Diagnostic)]
#[error("{file}:{line}:{column}: {message}")]
pub struct InvalidScene {
    /// File name for messages.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// What is wrong and what was expected.
    pub message: String,
    /// The scene text, for the caret display.
    #[source_code]
    pub src: NamedSource<String>,
    /// Where the problem is (byte offsets into the text).
    #[label("{label}")]
    pub span: SourceSpan,
    /// Short label under the caret.
    pub label: String,
    /// Optional hint.
    #[help]
    pub help: Option<String>,
}

impl SceneError {
    /// An error about bytes `span` of `text` (the scene read from `file`): computes the line
    /// and column and keeps the text for the caret display. Out-of-range or mid-character
    /// offsets are clamped to the text.
    pub(crate) fn at(
        text: &str,
        file: &str,
        span: std::ops::Range<usize>,
        message: impl Into<String>,
        label: impl Into<String>,
        help: Option<String>,
    ) -> Self {
        let start = floor_boundary(text, span.start);
        let end = ceil_boundary(text, span.end.max(start));
        let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
        let line = text[..start].matches('\n').count() + 1;
        let column = text[line_start..start].chars().count() + 1;
        SceneError::Invalid(Box::new(InvalidScene {
            file: file.to_string(),
            line,
            column,
            message: message.into(),
            src: NamedSource::new(file, text.to_string()),
            span: (start, end - start).into(),
            label: label.into(),
            help,
        }))
    }

    /// The 1-based `(line, column)` of the problem, for errors about the scene text.
    pub fn location(&self) -> Option<(usize, usize)> {
        match self {
            SceneError::Unreadable { .. } => None,
            SceneError::Invalid(e) => Some((e.line, e.column)),
        }
    }

    /// The message without the `file:line:column: ` prefix.
    pub fn message(&self) -> String {
        match self {
            SceneError::Unreadable { .. } => self.to_string(),
            SceneError::Invalid(e) => e.message.clone(),
        }
    }
}

/// The largest character boundary of `text` at or before `i` (clamped to the text).
pub(crate) fn floor_boundary(text: &str, i: usize) -> usize {
    let mut i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The smallest character boundary of `text` at or after `i` (clamped to the text).
pub(crate) fn ceil_boundary(text: &str, i: usize) -> usize {
    let mut i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i += 1;
    }
    i
}
