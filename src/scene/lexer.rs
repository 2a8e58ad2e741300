//! Splits one line of scene text into tokens: parentheses, commas, quoted strings and words
//! (keywords, names and numbers are all words; the parser decides which is which).

use std::ops::Range;

/// What kind of token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TokenKind {
    /// `(`
    Open,
    /// `)`
    Close,
    /// `,`
    Comma,
    /// `"…"`, on one line, without escapes; the span includes both quotes.
    Str,
    /// Any other run of characters up to whitespace, `(`, `)`, `,`, `"` or `#`.
    Word,
}

/// A token and where it is in the whole scene text (byte offsets).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Token {
    /// The kind.
    pub kind: TokenKind,
    /// Byte range in the whole text.
    pub span: Range<usize>,
}

impl Token {
    /// The byte range of a string token's contents (between the quotes).
    pub fn inner(&self) -> Range<usize> {
        self.span.start + 1..self.span.end - 1
    }
}

/// A lexical error: where and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LexError {
    /// Byte range in the whole text.
    pub span: Range<usize>,
    /// The message.
    pub message: String,
    /// Short label under the caret.
    pub label: String,
}

/// Characters that end a word.
fn ends_word(c: char) -> bool {
    c.is_whitespace() || c == '\u{feff}' || matches!(c, '(' | ')' | ',' | '"' | '#')
}

/// The tokens of `text[start..end]` (one line, without its `\n`), with spans relative to the
/// whole `text`. A `#` outside a string starts a comment that runs to the end of the line.
pub(crate) fn lex_line(text: &str, start: usize, end: usize) -> Result<Vec<Token>, LexError> {
    let line = &text[start..end];
    let mut tokens = Vec::new();
    let mut chars = line.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        let at = start + i;
        let single = |kind| Token {
            kind,
            span: at..at + 1,
        };
        match c {
            '#' => break,
            '(' => tokens.push(single(TokenKind::Open)),
            ')' => tokens.push(single(TokenKind::Close)),
            ',' => tokens.push(single(TokenKind::Comma)),
            '"' => match line[i + 1..].find('"') {
                Some(len) => {
                    let close = i + 1 + len;
                    tokens.push(Token {
                        kind: TokenKind::Str,
                        span: at..start + close + 1,
                    });
                    while chars.peek().is_some_and(|&(j, _)| j <= close) {
                        chars.next();
                    }
                }
                None => {
                    return Err(LexError {
                        span: at..at + 1,
                        message: "unterminated string: expected a closing `\"` on the same line"
                            .into(),
                        label: "this string is never closed".into(),
                    })
                }
            },
            c if ends_word(c) => {}
            _ => {
                let mut stop = line.len();
                while let Some(&(j, d)) = chars.peek() {
                    if ends_word(d) {
                        stop = j;
                        break;
                    }
                    chars.next();
                }
                tokens.push(Token {
                    kind: TokenKind::Word,
                    span: at..start + stop,
                });
            }
        }
    }
    Ok(tokens)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds_and_texts(text: &str) -> Vec<(TokenKind, &str)> {
        lex_line(text, 0, text.len())
            .unwrap()
            .into_iter()
            .map(|t| (t.kind, &text[t.span]))
            .collect()
    }

    #[test]
    fn splits_words_vectors_strings_and_comments() {
        use TokenKind::*;
        assert_eq!(
            kinds_and_texts("SPHERE (1,-2 3e1)\t0.5 \"x^2 # y\" red # comment (1)"),
            vec![
                (Word, "SPHERE"),
                (Open, "("),
                (Word, "1"),
                (Comma, ","),
                (Word, "-2"),
                (Word, "3e1"),
                (Close, ")"),
                (Word, "0.5"),
                (Str, "\"x^2 # y\""),
                (Word, "red"),
            ]
        );
    }

    #[test]
    fn spans_are_relative_to_the_whole_text() {
        let text = "a\n  b c\n";
        let toks = lex_line(text, 2, 7).unwrap();
        assert_eq!(toks[0].span, 4..5);
        assert_eq!(toks[1].span, 6..7);
    }

    #[test]
    fn unterminated_string_is_an_error() {
        let e = lex_line("IMPLICIT \"x^2", 0, 13).unwrap_err();
        assert_eq!(e.span, 9..10);
    }

    #[test]
    fn multibyte_text_does_not_panic() {
        let text = "é(ü,\"ß\")ñ#x";
        let toks = lex_line(text, 0, text.len()).unwrap();
        assert_eq!(toks.len(), 7);
        assert_eq!(&text[toks[5].span.clone()], ")");
        assert_eq!(&text[toks[6].span.clone()], "ñ");
    }
}
