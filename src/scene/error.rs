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
