//! Reading the arguments of one statement: numbers, vectors, colours and the end of the
//! line, each with an error that says what was expected at the offending token.

use std::fmt::Display;
use std::ops::Range;

use super::expr::{self, Fail, LetFail, Line, Names, Tapes};
use super::lexer::{Token, TokenKind};
use super::limits::{self, Limits};
use super::words::shorten;
use super::SceneError;
use crate::geometry::DVec3;

type Span = Range<usize>;
type Result<T> = std::result::Result<T, SceneError>;

/// The scene text and its name, for building errors.
#[derive(Clone, Copy)]
pub(super) struct Source<'a> {
    pub(super) text: &'a str,
    pub(super) name: &'a str,
}

impl Source<'_> {
    pub(super) fn error(
        &self,
        span: Span,
        message: impl Into<String>,
        label: impl Into<String>,
        help: Option<String>,
    ) -> SceneError {
        SceneError::at(self.text, self.name, span, message, label, help)
    }
}

/// A vector argument as written: its value, the span of `( … )` and of each component.
#[derive(Debug, Clone)]
pub(super) struct VecArg {
    pub(super) v: DVec3,
    pub(super) span: Span,
    pub(super) parts: [Span; 3],
}

/// Why a word is not a usable number.
#[derive(Debug, PartialEq)]
pub(super) enum NumberError {
    /// Not a number at all.
    NotANumber,
    /// NaN or infinite (written so, or too large for an f64); the reason in words.
    NotFinite(&'static str),
}

/// A finite f64 written in any notation Rust's `f64::from_str` accepts, other than NaN and
/// infinities (which are rejected with a reason).
pub(super) fn parse_number(s: &str) -> std::result::Result<f64, NumberError> {
    // A whole number of at most 15 digits (the `0` of a basis vector, a count) is below 2⁵³,
    // so its f64 is exact: the same value `f64::from_str` rounds to, without its parser.
    if (1..=15).contains(&s.len()) && s.bytes().all(|b| b.is_ascii_digit()) {
        let whole = s.bytes().fold(0u64, |n, b| n * 10 + u64::from(b - b'0'));
        return Ok(whole as f64);
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) if x.is_nan() => Err(NumberError::NotFinite("is not a number (NaN)")),
        Ok(_) if s.to_ascii_lowercase().contains("inf") => {
            Err(NumberError::NotFinite("is infinite"))
        }
        Ok(_) => Err(NumberError::NotFinite(
            "is too large: it overflows a 64-bit float to infinity",
        )),
        Err(_) => Err(NumberError::NotANumber),
    }
}

/// One line being parsed.
pub(super) struct Cursor<'a> {
    pub(super) src: Source<'a>,
    pub(super) tokens: Vec<Token>,
    pub(super) pos: usize,
    /// 1-based line number.
    pub(super) line: usize,
    /// Byte offset where the next line starts.
    pub(super) next_line: usize,
    /// The keyword of the statement being parsed, upper case (empty before it is known).
    pub(super) keyword: &'static str,
    /// Usage of the statement being parsed, shown as help.
    pub(super) usage: &'static str,
    /// Set while a part with a grammar of its own is read (a `<surface>`): its usage,
    /// shown in the help after the statement's.
    pub(super) part_usage: Option<&'static str>,
    /// The names expressions can use (`LET`, `clock`, …).
    pub(super) names: &'a Names,
    /// True once a value of this statement depended on the time: errors then name the frame.
    pub(super) uses_time: bool,
    /// Inside a `REPEAT`: the expressions of its body read so far, to compute again instead
    /// of reading their text at each iteration.
    pub(super) tapes: Option<&'a mut Tapes>,
}

impl<'a> Cursor<'a> {
    pub(super) fn text(&self, t: &Token) -> &'a str {
        &self.src.text[t.span.clone()]
    }

    pub(super) fn peek(&self) -> Option<Token> {
        self.tokens.get(self.pos).cloned()
    }

    pub(super) fn peek_kind(&self) -> Option<TokenKind> {
        self.tokens.get(self.pos).map(|t| t.kind)
    }

    /// The next token's text if it is a word.
    pub(super) fn peek_word(&self) -> Option<&'a str> {
        match self.tokens.get(self.pos) {
            Some(t) if t.kind == TokenKind::Word => Some(self.text(t)),
            _ => None,
        }
    }

    /// The span of the next token, or an empty span at the end of the line's last token.
    pub(super) fn here(&self) -> Span {
        match self.tokens.get(self.pos) {
            Some(t) => t.span.clone(),
            None => {
                let end = self.tokens.last().map_or(0, |t| t.span.end);
                end..end
            }
        }
    }

    /// From the start of `a` to the end of `b`.
    pub(super) fn join(a: &Span, b: &Span) -> Span {
        a.start..b.end
    }

    /// The span of the statement's keyword (its first token).
    pub(super) fn statement_keyword_span(&self) -> Span {
        self.tokens.first().map_or(0..0, |t| t.span.clone())
    }

    /// The whole statement written so far (keyword to last token).
    pub(super) fn statement_span(&self) -> Span {
        let first = self.tokens.first().map_or(0, |t| t.span.start);
        let last = self.tokens.last().map_or(first, |t| t.span.end);
        first..last
    }

    pub(super) fn describe(&self, t: Option<&Token>) -> String {
        match t {
            None => "end of line".into(),
            Some(t) => match t.kind {
                TokenKind::Open => "`(`".into(),
                TokenKind::Close => "`)`".into(),
                TokenKind::Comma => "`,`".into(),
                TokenKind::Str => format!("the string {}", shorten(self.text(t), 30)),
                TokenKind::Word => {
                    let s = self.text(t);
                    if parse_number(s) == Err(NumberError::NotANumber) {
                        format!("`{}`", shorten(s, 30))
                    } else {
                        format!("the number `{}`", shorten(s, 30))
                    }
                }
            },
        }
    }

    pub(super) fn usage_help(&self) -> Option<String> {
        (!self.usage.is_empty()).then(|| match self.part_usage {
            Some(part) => format!("usage: {}\n{part}", self.usage),
            None => format!("usage: {}", self.usage),
        })
    }

    /// An error at `span` with the statement's usage as help.
    pub(super) fn fail(
        &self,
        span: Span,
        message: impl Into<String>,
        label: impl Into<String>,
    ) -> SceneError {
        let message = self.at_frame(message.into());
        self.src.error(span, message, label, self.usage_help())
    }

    /// `message`, naming the frame when a value of the statement depended on the time.
    fn at_frame(&self, message: String) -> String {
        if self.uses_time {
            message + &self.names.frame_note()
        } else {
            message
        }
    }

    /// An error at `span` with the given help.
    pub(super) fn fail_help(
        &self,
        span: Span,
        message: impl Into<String>,
        label: impl Into<String>,
        help: impl Into<String>,
    ) -> SceneError {
        let message = self.at_frame(message.into());
        self.src.error(span, message, label, Some(help.into()))
    }

    /// "expected …, found …" at the next token.
    pub(super) fn unexpected(&self, expected: &str) -> SceneError {
        let found = self.describe(self.peek().as_ref());
        self.fail(
            self.here(),
            format!("expected {expected}, found {found}"),
            format!("expected {expected}"),
        )
    }

    /// A finite number: a number as written, or an expression (see `expr`).
    pub(super) fn number(&mut self, what: impl Display + Copy) -> Result<(f64, Span)> {
        let Some(t) = self
            .peek()
            .filter(|t| matches!(t.kind, TokenKind::Word | TokenKind::Open))
        else {
            return Err(self.unexpected(&format!("{what} (a number)")));
        };
        let s = self.text(&t);
        match parse_number(s) {
            Ok(x) if !expr::continues(&self.line()) => {
                self.pos += 1;
                return Ok((x, t.span));
            }
            Err(NumberError::NotFinite(reason)) => {
                return Err(self.fail(
                    t.span,
                    format!(
                        "{what} must be a finite number, but `{}` {reason}",
                        shorten(s, 30)
                    ),
                    "not a finite number",
                ))
            }
            _ => {}
        }
        let start = t.span.start;
        if let Some(tapes) = self.tapes.as_deref_mut() {
            if let Some((value, uses_time, span, next_token)) =
                tapes.eval(start, self.src.text, self.names)
            {
                self.uses_time |= uses_time;
                self.pos = next_token;
                return Ok((value, span));
            }
        }
        let (read, uses_time) = expr::read(&self.line());
        self.uses_time |= uses_time;
        match read {
            Ok(Some(read)) => {
                self.pos = read.next_token;
                if let Some(tapes) = self.tapes.as_deref_mut() {
                    tapes.keep(start, read.tape);
                }
                Ok((read.value, read.span))
            }
            Ok(None) => Err(self.unexpected(&format!("{what} (a number)"))),
            Err(fail) => Err(self.expression_error(what, fail)),
        }
    }

    /// The rest of the line as an expression reads it.
    fn line(&self) -> Line<'_> {
        Line {
            text: self.src.text,
            tokens: &self.tokens,
            pos: self.pos,
            names: self.names,
        }
    }

    /// The error for an expression read as `what` that failed.
    fn expression_error(&self, what: impl Display, fail: Fail) -> SceneError {
        match fail {
            Fail::NotAnExpression => self.unexpected(&format!("{what} (a number)")),
            Fail::Syntax {
                span,
                message,
                label,
                help,
            } => {
                let message = format!("in {what}: {message}");
                match help {
                    Some(h) => self.fail_help(span, message, label, h),
                    None => self.fail(span, message, label),
                }
            }
            Fail::Value { span, message } => self.fail(
                span,
                format!("{what} cannot be computed: {message}"),
                "here",
            ),
        }
    }

    /// A `LET name = expression` statement after its keyword, to the end of the line: the
    /// name, its value, whether the value depends on the time, and the span of the name.
    pub(super) fn let_definition(&mut self) -> Result<(String, f64, bool, Span)> {
        let (read, uses_time) = expr::read_let(&self.line());
        self.uses_time |= uses_time;
        match read {
            Ok(d) => {
                self.pos = d.next_token;
                self.end()?;
                Ok((d.name, d.value, d.uses_time, d.name_span))
            }
            Err(LetFail::Expected { what, at }) => {
                self.pos = at;
                Err(self.unexpected(&what))
            }
            Err(LetFail::At {
                span,
                message,
                label,
            }) => Err(self.fail(span, message, label)),
            Err(LetFail::Expression { what, fail }) => Err(self.expression_error(&what, fail)),
        }
    }

    /// A number within `limits`; outside them, an error that states the range. Every
    /// bounded number of the scene language is read here, through [`Cursor::number`].
    pub(super) fn number_in(
        &mut self,
        what: impl Display + Copy,
        limits: &Limits,
    ) -> Result<(f64, Span)> {
        let (x, span) = self.number(what)?;
        self.check(x, &span, what, limits)?;
        Ok((x, span))
    }

    /// A whole number within `limits` (whole ones, of at most `u32::MAX`).
    pub(super) fn whole_in(
        &mut self,
        what: impl Display + Copy,
        limits: &Limits,
    ) -> Result<(u32, Span)> {
        debug_assert!(limits.whole && limits.max <= u32::MAX as f64);
        let (x, span) = self.number_in(what, limits)?;
        Ok((x as u32, span))
    }

    /// Fails unless `x` (written at `span`) is within `limits`.
    pub(super) fn check(
        &self,
        x: f64,
        span: &Span,
        what: impl Display + Copy,
        limits: &Limits,
    ) -> Result<()> {
        if limits.contains(x) {
            return Ok(());
        }
        let (requirement, label) = limits.violation(x);
        let range = if limits.whole || limits.between {
            String::new()
        } else {
            format!(" (the valid range is {limits})")
        };
        Err(self.fail(
            span.clone(),
            format!("{what} must be {requirement}, not {}{range}", show_value(x)),
            label,
        ))
    }

    /// A vector `(a, b, c)`; commas are optional. `names` name the components in messages.
    pub(super) fn vector(&mut self, what: impl Display + Copy, names: [&str; 3]) -> Result<VecArg> {
        let open = match self.peek() {
            Some(t) if t.kind == TokenKind::Open => t.span,
            _ => {
                return Err(self.unexpected(&format!(
                    "{what}, a vector ({}, {}, {})",
                    names[0], names[1], names[2]
                )))
            }
        };
        self.pos += 1;
        let mut v = [0.0; 3];
        let mut parts = [0..0, 0..0, 0..0];
        for i in 0..3 {
            if i > 0 && self.peek_kind() == Some(TokenKind::Comma) {
                self.pos += 1;
            }
            if self.peek_kind() == Some(TokenKind::Close) {
                return Err(self.fail(
                    self.here(),
                    format!(
                        "{what} has only {i} number{}: a vector needs 3, written ({}, {}, {})",
                        if i == 1 { "" } else { "s" },
                        names[0],
                        names[1],
                        names[2]
                    ),
                    format!("expected the {} component", names[i]),
                ));
            }
            // The name is formatted only if a message needs it.
            let (x, span) = self.number(format_args!("the {} component of {what}", names[i]))?;
            v[i] = x;
            parts[i] = span;
        }
        if let Some(t) = self.peek().filter(|t| t.kind == TokenKind::Close) {
            self.pos += 1;
            return Ok(VecArg {
                v: DVec3::from_array(v),
                span: open.start..t.span.end,
                parts,
            });
        }
        // Too many components?
        let mut k = self.pos;
        if self.tokens.get(k).map(|t| t.kind) == Some(TokenKind::Comma) {
            k += 1;
        }
        if let Some(t) = self.tokens.get(k) {
            if t.kind == TokenKind::Word && parse_number(self.text(t)).is_ok() {
                return Err(self.fail(
                    t.span.clone(),
                    format!("too many numbers in {what}: a vector has exactly 3 components"),
                    "extra number",
                ));
            }
        }
        Err(self.unexpected(&format!("`)` to close {what}")))
    }

    /// A point, each coordinate within [`limits::COORDINATE`].
    pub(super) fn point(&mut self, what: impl Display + Copy) -> Result<VecArg> {
        let a = self.vector(what, ["x", "y", "z"])?;
        for (i, name) in ["x", "y", "z"].iter().enumerate() {
            self.check(
                a.v[i],
                &a.parts[i],
                format_args!("the {name} component of {what}"),
                &limits::COORDINATE,
            )?;
        }
        Ok(a)
    }

    /// A direction: a point-like vector whose length is within [`limits::DIRECTION_LENGTH`].
    pub(super) fn direction(&mut self, what: impl Display + Copy) -> Result<VecArg> {
        let a = self.point(what)?;
        if a.v == DVec3::ZERO {
            return Err(self.fail(
                a.span,
                format!("{what} is the zero vector, but it must give a direction"),
                "zero-length vector",
            ));
        }
        let length = a.v.length();
        if !limits::DIRECTION_LENGTH.contains(length) {
            return Err(self.fail(
                a.span,
                format!(
                    "{what} is too short to give a direction: its length must be {}, not {}",
                    limits::DIRECTION_LENGTH,
                    show_value(length)
                ),
                "too short",
            ));
        }
        Ok(a)
    }

    /// A colour, each component within `limits` (which start at 0).
    pub(super) fn colour(&mut self, what: impl Display + Copy, limits: &Limits) -> Result<VecArg> {
        let a = self.vector(what, ["r", "g", "b"])?;
        for (i, name) in ["red", "green", "blue"].iter().enumerate() {
            if a.v[i] < 0.0 {
                return Err(self.fail(
                    a.parts[i].clone(),
                    format!(
                        "the {name} component of {what} must not be negative, not {} (the \
                         valid range is {limits})",
                        show_value(a.v[i])
                    ),
                    "negative colour component",
                ));
            }
            self.check(
                a.v[i],
                &a.parts[i],
                format_args!("the {name} component of {what}"),
                limits,
            )?;
        }
        Ok(a)
    }

    /// The end of the statement.
    pub(super) fn end(&self) -> Result<()> {
        match self.peek() {
            None => Ok(()),
            Some(_) => Err(self.unexpected("end of line")),
        }
    }
}

/// A value as messages write it: as written for short numbers (`-1`, `2.5`, `40000`), in
/// exponent form for long ones (`1e308`, `5e-324`).
pub(super) fn show_value(x: f64) -> String {
    let plain = format!("{x}");
    if plain.len() <= 12 {
        plain
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_any_notation_but_finite() {
        for (s, x) in [
            ("1", 1.0),
            ("-2.5", -2.5),
            ("+.5", 0.5),
            ("1e3", 1e3),
            ("2.E-2", 0.02),
        ] {
            assert_eq!(parse_number(s), Ok(x), "{s}");
        }
        for s in ["nan", "NaN", "inf", "-Infinity", "1e999", "-1e400"] {
            assert!(
                matches!(parse_number(s), Err(NumberError::NotFinite(_))),
                "{s}"
            );
        }
        for s in ["abc", "1.2.3", "0x10", "", "1e"] {
            assert_eq!(parse_number(s), Err(NumberError::NotANumber), "{s}");
        }
    }

    #[test]
    fn whole_numbers_read_as_the_standard_parser_reads_them() {
        // Every length up to and beyond the shortcut's 15 digits, leading zeros, the
        // largest of each length and the neighbours of 2⁵³.
        let mut words: Vec<String> = vec!["0".into(), "000".into(), "0009".into()];
        let mut x: u64 = 0x2545_f491_4f6c_dd1d;
        for len in 1..=20 {
            words.push("9".repeat(len));
            words.push(format!("1{}", "0".repeat(len - 1)));
            for _ in 0..200 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let digits: String = (0..len)
                    .map(|k| char::from(b'0' + ((x >> (3 * (k % 20))) % 10) as u8))
                    .collect();
                words.push(digits);
            }
        }
        for n in [(1u64 << 53) - 1, 1 << 53, (1 << 53) + 1] {
            words.push(n.to_string());
        }
        for w in &words {
            let want = w.parse::<f64>().unwrap();
            assert_eq!(parse_number(w).map(f64::to_bits), Ok(want.to_bits()), "{w}");
        }
    }
}
