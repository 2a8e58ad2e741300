//! Expressions wherever the scene language takes a number, `LET` names, and the animation
//! time (`clock`, `frame`, `frames`) they may depend on.
//!
//! Grammar, over the line's tokens (a word such as `0.6*clock` is split further):
//!
//! ```text
//! sum     := product { ('+' | '-') product }
//! product := unary { ('*' | '/') unary }
//! unary   := ('-' | '+') unary | power
//! power   := primary [ '^' unary ]              (right associative; -2^2 = -(2^2))
//! primary := number | name | function '(' sum { ',' sum } ')' | '(' sum ')'
//! ```
//!
//! Angles are in radians (`sin(2*pi*clock)`). In a list of values (a vector, or numbers one
//! after another), a `+` or `-` with a space before it and none after it starts the next value,
//! so `(1 -2 3)` stays three numbers while `(1 - 2 3)` and `(1-2 3)` are two; inside
//! parentheses and in `LET` every `+` and `-` is an operator.

use std::collections::HashMap;
use std::ops::Range;

use super::lexer::{Token, TokenKind};
use super::words::{shorten, suggest};

type Span = Range<usize>;

/// Deepest nesting of parentheses, signs and powers accepted.
const MAX_NESTING: usize = 100;

/// Functions with their least and greatest number of arguments.
const FUNCTIONS: &[(&str, usize, usize)] = &[
    ("sin", 1, 1),
    ("cos", 1, 1),
    ("tan", 1, 1),
    ("sqrt", 1, 1),
    ("cbrt", 1, 1),
    ("exp", 1, 1),
    ("log", 1, 1),
    ("abs", 1, 1),
    ("min", 2, usize::MAX),
    ("max", 2, usize::MAX),
];

/// Names with a built-in value.
const CONSTANTS: &[&str] = &["clock", "frame", "frames", "pi"];

/// Names a `LET` may not take: the built-ins, the functions and the variables of equations.
pub(super) fn is_reserved(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    CONSTANTS.contains(&lower.as_str())
        || FUNCTIONS.iter().any(|f| f.0 == lower)
        || matches!(lower.as_str(), "x" | "y" | "z" | "nan" | "inf" | "infinity")
}

/// Which frame of an animation a scene is read for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameTime {
    /// The frame number, from 0 (the first frame) to `count - 1`.
    pub frame: u32,
    /// How many frames the animation has (at least 1).
    pub count: u32,
}

impl FrameTime {
    /// `clock`: 0 at the first frame, 1 at the last (0 when there is only one frame).
    pub fn clock(self) -> f64 {
        if self.count > 1 {
            f64::from(self.frame) / f64::from(self.count - 1)
        } else {
            0.0
        }
    }
}

/// A value defined by `LET`.
#[derive(Debug, Clone)]
struct Defined {
    value: f64,
    line: usize,
    uses_time: bool,
}

/// Hashes a name by FNV-1a, 64 bits: names are short and chosen by the scene's author, so
/// the standard library's SipHash (resistant to chosen keys) cost more than the rest of a
/// lookup; a `REPEAT` of thousands of objects looks a name up for each of its values.
#[derive(Debug, Clone, Copy)]
struct NameHasher(u64);

impl Default for NameHasher {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl std::hash::Hasher for NameHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// The names an expression can use: the built-ins and the `LET` definitions read so far.
#[derive(Debug)]
pub(super) struct Names {
    lets: HashMap<String, Defined, std::hash::BuildHasherDefault<NameHasher>>,
    /// The frame being read; `None` reads the scene as a still (frame 0 of 1).
    pub(super) time: Option<FrameTime>,
}

impl Names {
    /// No `LET` names yet, at the given time.
    pub(super) fn new(time: Option<FrameTime>) -> Self {
        Self {
            lets: HashMap::default(),
            time,
        }
    }

    /// The line a `LET` (or a `REPEAT`) defined `name` on, if one did.
    pub(super) fn defined_on(&self, name: &str) -> Option<usize> {
        self.lets.get(name).map(|d| d.line)
    }

    /// Forgets the definition of `name` (a `REPEAT`'s variable after its loop, a `LET` of a
    /// loop's body after each iteration).
    pub(super) fn forget(&mut self, name: &str) {
        self.lets.remove(name);
    }

    /// The value of `name` and whether it depends on the time, if it has one.
    pub(super) fn value(&self, name: &str) -> Option<(f64, bool)> {
        let t = self.time.unwrap_or(FrameTime { frame: 0, count: 1 });
        match name {
            "clock" => Some((t.clock(), true)),
            "frame" => Some((f64::from(t.frame), true)),
            "frames" => Some((f64::from(t.count), true)),
            "pi" | "PI" | "Pi" | "pI" => Some((std::f64::consts::PI, false)),
            _ => self.lets.get(name).map(|d| (d.value, d.uses_time)),
        }
    }

    /// `LET` names in alphabetical order.
    fn defined(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.lets.keys().map(String::as_str).collect();
        names.sort_unstable();
        names
    }

    /// The words after which a frame is named in an error: `" (at frame 3 of 0..=9, clock = 0.3333)"`.
    pub(super) fn frame_note(&self) -> String {
        match self.time {
            Some(t) => format!(
                " (at frame {} of 0..={}, clock = {})",
                t.frame,
                t.count.saturating_sub(1),
                round4(t.clock())
            ),
            None => String::new(),
        }
    }
}

/// `x` to 4 decimals, without trailing zeros.
fn round4(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// What a piece of a line is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tk {
    Num,
    Name,
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    Equals,
    Open,
    Close,
    Comma,
    /// A character that is not part of any expression.
    Bad,
}

/// A piece of the line: a token of the lexer, or part of a word.
#[derive(Debug, Clone)]
struct Piece {
    tk: Tk,
    span: Span,
    /// Index of the lexer token it is part of.
    token: usize,
    /// True for the last piece of its lexer token.
    last: bool,
    /// Whitespace (or the start of the line) just before it.
    space_before: bool,
    /// Whitespace (or the end of the line) just after it.
    space_after: bool,
}

/// The rest of one line from a token on, and the names in scope: what an expression is read
/// from (the statement reader hands over its position).
#[derive(Clone, Copy)]
pub(super) struct Line<'a> {
    /// The whole scene text (the tokens' spans index it).
    pub(super) text: &'a str,
    /// The line's tokens.
    pub(super) tokens: &'a [Token],
    /// The token the expression starts at.
    pub(super) pos: usize,
    /// The names expressions can use.
    pub(super) names: &'a Names,
}

/// The pieces of the line's tokens from `line.pos` up to the first string, or to the first
/// comma or unmatched `)` outside parentheses.
fn pieces(line: &Line) -> Vec<Piece> {
    let text = line.text;
    let is_space = |c: Option<char>| c.is_none_or(char::is_whitespace);
    // Room for a usual number's pieces at once.
    let mut out = Vec::with_capacity(16);
    let mut depth = 0usize;
    for (index, t) in line.tokens.iter().enumerate().skip(line.pos) {
        let mut push = |tk, span: Span, last| {
            out.push(Piece {
                tk,
                space_before: is_space(text[..span.start].chars().next_back()),
                space_after: is_space(text[span.end..].chars().next()),
                span,
                token: index,
                last,
            })
        };
        match t.kind {
            TokenKind::Open => {
                depth += 1;
                push(Tk::Open, t.span.clone(), true)
            }
            // A comma or an unmatched `)` at the outer level ends any expression: stop there,
            // so reading each number of a long line costs only its own tokens.
            TokenKind::Close | TokenKind::Comma if depth == 0 => break,
            TokenKind::Close => {
                depth -= 1;
                push(Tk::Close, t.span.clone(), true)
            }
            TokenKind::Comma => push(Tk::Comma, t.span.clone(), true),
            TokenKind::Str => break,
            TokenKind::Word => {
                for (tk, span) in split_word(text, t.span.clone()) {
                    let last = span.end == t.span.end;
                    push(tk, span, last);
                }
            }
        }
    }
    out
}

/// A word split into numbers, names and operators (a bad character ends it), piece by
/// piece: nothing is allocated, so that reading a number costs only its own characters.
fn split_word(text: &str, word: Span) -> WordPieces<'_> {
    WordPieces {
        bytes: text.as_bytes(),
        at: word.start,
        end: word.end,
    }
}

/// The pieces of one word ([`split_word`]).
struct WordPieces<'a> {
    /// The whole text's bytes.
    bytes: &'a [u8],
    /// Where the next piece starts.
    at: usize,
    /// Where the word ends.
    end: usize,
}

impl Iterator for WordPieces<'_> {
    type Item = (Tk, Span);

    fn next(&mut self) -> Option<(Tk, Span)> {
        let (b, end) = (self.bytes, self.end);
        let digits = |mut i: usize| {
            while i < end && b[i].is_ascii_digit() {
                i += 1;
            }
            i
        };
        let start = self.at;
        if start >= end {
            return None;
        }
        let c = b[start];
        let mut i = start;
        let op = match c {
            b'+' => Some(Tk::Plus),
            b'-' => Some(Tk::Minus),
            b'*' => Some(Tk::Star),
            b'/' => Some(Tk::Slash),
            b'^' => Some(Tk::Caret),
            b'=' => Some(Tk::Equals),
            _ => None,
        };
        let tk = if let Some(tk) = op {
            i += 1;
            tk
        } else if c.is_ascii_digit() || c == b'.' {
            i = digits(i);
            if i < end && b[i] == b'.' {
                i = digits(i + 1);
            }
            if i < end && (b[i] == b'e' || b[i] == b'E') {
                let mut j = i + 1;
                if j < end && (b[j] == b'+' || b[j] == b'-') {
                    j += 1;
                }
                let k = digits(j);
                if k > j {
                    i = k;
                }
            }
            Tk::Num
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while i < end && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            Tk::Name
        } else {
            i = end;
            Tk::Bad
        };
        self.at = i;
        Some((tk, start..i))
    }
}

/// Why an expression could not be read.
pub(super) enum Fail {
    /// Not written as an expression: the caller reports what it expected instead.
    NotAnExpression,
    /// A mistake in how the expression is written.
    Syntax {
        span: Span,
        message: String,
        label: String,
        help: Option<String>,
    },
    /// Written correctly, but its value cannot be computed (or is not finite).
    Value { span: Span, message: String },
}

fn syntax(span: Span, message: impl Into<String>, label: impl Into<String>) -> Fail {
    Fail::Syntax {
        span,
        message: message.into(),
        label: label.into(),
        help: None,
    }
}

/// Reads one expression from a list of pieces, computing its value as it goes.
struct Reader<'r> {
    text: &'r str,
    names: &'r Names,
    pieces: Vec<Piece>,
    at: usize,
    /// Open parentheses around the current position.
    parens: usize,
    depth: usize,
    /// In a list of values (the space rule for `+` and `-` applies at the outer level).
    list: bool,
    uses_time: bool,
    /// The steps of the value computed so far, in the order they were taken.
    tape: Vec<Op>,
}

type Value = (f64, Span);

impl<'r> Reader<'r> {
    fn peek(&self) -> Option<&Piece> {
        self.pieces.get(self.at)
    }

    fn peek_tk(&self) -> Option<Tk> {
        self.peek().map(|p| p.tk)
    }

    /// The span of the next piece, or an empty span after the last one consumed.
    fn here(&self) -> Span {
        match self.peek() {
            Some(p) => p.span.clone(),
            None => {
                let end = self.pieces.last().map_or(0, |p| p.span.end);
                end..end
            }
        }
    }

    fn piece_text(&self, p: &Piece) -> &str {
        &self.text[p.span.clone()]
    }

    fn found(&self) -> String {
        match self.peek() {
            None => "end of line".into(),
            Some(p) => format!("`{}`", shorten(self.piece_text(p), 30)),
        }
    }

    fn finite(&self, x: f64, span: &Span, what: &str) -> Result<f64, Fail> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(Fail::Value {
                span: span.clone(),
                message: format!("{what} is too large: it overflows a 64-bit float"),
            })
        }
    }

    fn sum(&mut self) -> Result<Value, Fail> {
        let (mut x, mut span) = self.product()?;
        while let Some(p) = self.peek().filter(|p| matches!(p.tk, Tk::Plus | Tk::Minus)) {
            if self.list && self.parens == 0 && p.space_before && !p.space_after {
                break; // `1 -2`: the sign of the next value
            }
            let minus = p.tk == Tk::Minus;
            self.at += 1;
            let (y, ys) = self.product()?;
            span = span.start..ys.end;
            x = self.finite(if minus { x - y } else { x + y }, &span, "the sum")?;
            self.tape.push(if minus { Op::Subtract } else { Op::Add });
        }
        Ok((x, span))
    }

    fn product(&mut self) -> Result<Value, Fail> {
        let (mut x, mut span) = self.unary()?;
        while let Some(p) = self.peek().filter(|p| matches!(p.tk, Tk::Star | Tk::Slash)) {
            let divide = p.tk == Tk::Slash;
            self.at += 1;
            let (y, ys) = self.unary()?;
            if divide && y == 0.0 {
                return Err(Fail::Value {
                    message: format!(
                        "division by zero: `{}` is 0",
                        shorten(&self.text[ys.clone()], 30)
                    ),
                    span: ys,
                });
            }
            span = span.start..ys.end;
            x = self.finite(if divide { x / y } else { x * y }, &span, "the product")?;
            self.tape
                .push(if divide { Op::Divide } else { Op::Multiply });
        }
        Ok((x, span))
    }

    fn unary(&mut self) -> Result<Value, Fail> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(syntax(
                self.here(),
                format!("the expression is nested too deeply (more than {MAX_NESTING} levels)"),
                "too deep",
            ));
        }
        let r = match self.peek().map(|p| (p.tk, p.span.clone())) {
            Some((Tk::Minus, s)) => {
                self.at += 1;
                let r = self.unary().map(|(x, e)| (-x, s.start..e.end));
                self.tape.push(Op::Negate);
                r
            }
            Some((Tk::Plus, s)) => {
                self.at += 1;
                self.unary().map(|(x, e)| (x, s.start..e.end))
            }
            _ => self.power(),
        };
        self.depth -= 1;
        r
    }

    fn power(&mut self) -> Result<Value, Fail> {
        let (base, bs) = self.primary()?;
        if self.peek_tk() != Some(Tk::Caret) {
            return Ok((base, bs));
        }
        self.at += 1;
        let (exp, es) = self.unary()?;
        let span = bs.start..es.end;
        let x = base.powf(exp);
        if base == 0.0 && exp < 0.0 {
            return Err(Fail::Value {
                span,
                message: format!("division by zero: 0 to the negative power {exp}"),
            });
        }
        if x.is_nan() {
            return Err(Fail::Value {
                span,
                message: format!(
                    "{base} to the power {exp} is not a real number (a negative number to a \
                     power that is not whole)"
                ),
            });
        }
        let x = self.finite(x, &span, "the power")?;
        self.tape.push(Op::Power);
        Ok((x, span))
    }

    fn primary(&mut self) -> Result<Value, Fail> {
        let Some(p) = self.peek().cloned() else {
            return Err(syntax(
                self.here(),
                "the expression ends too early: expected a number, a name or `(`",
                "expected a value",
            ));
        };
        let source: &'r str = self.text;
        let text = &source[p.span.clone()];
        match p.tk {
            Tk::Num => {
                self.at += 1;
                match text.parse::<f64>() {
                    Ok(x) if x.is_finite() => {
                        self.tape.push(Op::Number(x));
                        Ok((x, p.span))
                    }
                    Ok(_) => Err(Fail::Value {
                        span: p.span,
                        message: format!(
                            "`{}` is too large: it overflows a 64-bit float to infinity",
                            shorten(text, 30)
                        ),
                    }),
                    Err(_) => Err(syntax(
                        p.span,
                        format!("`{}` is not a number", shorten(text, 30)),
                        "not a number",
                    )),
                }
            }
            Tk::Name => {
                self.at += 1;
                if let Some(&(name, lo, hi)) = FUNCTIONS.iter().find(|f| f.0 == text) {
                    return self.call(name, lo, hi, p.span);
                }
                match self.names.value(text) {
                    Some((x, uses_time)) => {
                        self.uses_time |= uses_time;
                        self.tape.push(Op::Name(p.span.clone()));
                        Ok((x, p.span))
                    }
                    None => Err(self.unknown_name(text, p.span)),
                }
            }
            Tk::Open => {
                self.at += 1;
                self.parens += 1;
                let inner = self.sum()?;
                self.parens -= 1;
                match self.peek_tk() {
                    Some(Tk::Close) => {
                        let close = self.here();
                        self.at += 1;
                        Ok((inner.0, p.span.start..close.end))
                    }
                    Some(Tk::Comma) => Err(syntax(
                        self.here(),
                        "expected `)`, found `,`: parentheses in a number group one \
                         expression (a vector is not allowed here)",
                        "expected `)`",
                    )),
                    _ => Err(syntax(
                        self.here(),
                        format!("expected an operator or `)`, found {}", self.found()),
                        "expected `)`",
                    )),
                }
            }
            _ => Err(syntax(
                p.span,
                format!(
                    "expected a number, a name or `(`, found `{}`",
                    shorten(text, 30)
                ),
                "expected a value",
            )),
        }
    }

    fn call(
        &mut self,
        name: &'static str,
        lo: usize,
        hi: usize,
        span: Span,
    ) -> Result<Value, Fail> {
        if self.peek_tk() != Some(Tk::Open) {
            return Err(syntax(
                span,
                format!("`{name}` is a function: write {name}(…)"),
                "expected `(` after it",
            ));
        }
        self.at += 1;
        self.parens += 1;
        let mut args = vec![self.sum()?];
        while self.peek_tk() == Some(Tk::Comma) {
            self.at += 1;
            args.push(self.sum()?);
        }
        self.parens -= 1;
        if self.peek_tk() != Some(Tk::Close) {
            return Err(syntax(
                self.here(),
                format!(
                    "expected `,` or `)` in the arguments of {name}, found {}",
                    self.found()
                ),
                "expected `)`",
            ));
        }
        let whole = span.start..self.here().end;
        self.at += 1;
        if args.len() < lo || args.len() > hi {
            let wanted = match (lo, hi) {
                (1, 1) => "one argument".to_string(),
                (l, usize::MAX) => format!("at least {l} arguments"),
                (l, h) => format!("{l} to {h} arguments"),
            };
            return Err(syntax(
                whole,
                format!("{name} takes {wanted}, not {}", args.len()),
                "wrong number of arguments",
            ));
        }
        let values: Vec<f64> = args.iter().map(|v| v.0).collect();
        let x = apply(name, &values).map_err(|message| Fail::Value {
            span: args[0].1.clone(),
            message,
        })?;
        let x = self.finite(x, &whole, "the result")?;
        self.tape.push(Op::Call(name, values.len()));
        Ok((x, whole))
    }

    fn unknown_name(&self, name: &str, span: Span) -> Fail {
        let defined = self.names.defined();
        let mut candidates = defined.clone();
        candidates.extend(CONSTANTS);
        let help = match suggest(name, candidates.iter().copied()) {
            Some(s) => Some(format!("did you mean `{s}`?")),
            None if defined.is_empty() => Some(format!(
                "define it before this line with `LET {name} = …`; built-in names: {}",
                CONSTANTS.join(", ")
            )),
            None => Some(format!(
                "names defined so far: {}; built-in: {}",
                defined.join(", "),
                CONSTANTS.join(", ")
            )),
        };
        Fail::Syntax {
            span,
            message: format!("unknown name `{}`", shorten(name, 30)),
            label: "not defined before this line".into(),
            help,
        }
    }
}

/// The function `name` (one of [`FUNCTIONS`]) of `args` (as many as it takes), or why it
/// has no value (said of its first argument).
fn apply(name: &str, args: &[f64]) -> Result<f64, String> {
    let a = args[0];
    Ok(match name {
        "sin" => a.sin(),
        "cos" => a.cos(),
        "tan" => a.tan(),
        "abs" => a.abs(),
        "cbrt" => a.cbrt(),
        "exp" => a.exp(),
        "log" => {
            if a <= 0.0 {
                return Err(format!("log of a number that is not positive ({a})"));
            }
            a.ln()
        }
        "sqrt" => {
            if a < 0.0 {
                return Err(format!("sqrt of a negative number ({a})"));
            }
            a.sqrt()
        }
        "min" => args.iter().copied().fold(f64::INFINITY, f64::min),
        "max" => args.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        _ => unreachable!("every function is evaluated"),
    })
}

/// One step of an expression's computation, as [`Tape`] keeps it.
#[derive(Debug, Clone)]
enum Op {
    /// A number as written.
    Number(f64),
    /// The value of the name written at this span of the scene text.
    Name(Span),
    /// The negation of the last value.
    Negate,
    /// The last two values added (the earlier one first).
    Add,
    /// The earlier of the last two values minus the later.
    Subtract,
    /// The last two values multiplied.
    Multiply,
    /// The earlier of the last two values divided by the later.
    Divide,
    /// The earlier of the last two values to the power of the later.
    Power,
    /// The function of the last values (this many of them, in the order written).
    Call(&'static str, usize),
}

/// An expression read once, kept so that a `REPEAT` computes it again at each iteration
/// without reading its text: the reader's steps in the order it took them (postfix), its
/// span and the token after it, which do not depend on the names' values.
#[derive(Debug, Clone)]
pub(super) struct Tape {
    ops: Vec<Op>,
    /// Where the expression is written.
    pub(super) span: Span,
    /// The token after it.
    pub(super) next_token: usize,
}

impl Tape {
    /// The expression's value with the names' current values, and whether it depended on the
    /// time; computed by the reader's operations in the reader's order, so the same value to
    /// the bit. `None` wherever the reader would fail (a name not defined, a division by zero,
    /// a value not finite or not real): the caller then reads the text again for the error.
    /// `stack` is scratch space (left empty).
    pub(super) fn eval(
        &self,
        text: &str,
        names: &Names,
        stack: &mut Vec<f64>,
    ) -> Option<(f64, bool)> {
        stack.clear();
        let mut uses_time = false;
        let finite = |x: f64| x.is_finite().then_some(x);
        for op in &self.ops {
            let x = match op {
                Op::Number(x) => *x,
                Op::Name(span) => {
                    let (x, time) = names.value(&text[span.clone()])?;
                    uses_time |= time;
                    x
                }
                Op::Negate => -stack.pop()?,
                Op::Call(name, count) => {
                    let args = stack.split_off(stack.len().checked_sub(*count)?);
                    finite(apply(name, &args).ok()?)?
                }
                binary => {
                    let y = stack.pop()?;
                    let x = stack.pop()?;
                    match binary {
                        Op::Add => finite(x + y)?,
                        Op::Subtract => finite(x - y)?,
                        Op::Multiply => finite(x * y)?,
                        Op::Divide if y == 0.0 => return None,
                        Op::Divide => finite(x / y)?,
                        Op::Power if x == 0.0 && y < 0.0 => return None,
                        Op::Power => finite(x.powf(y))?,
                        _ => unreachable!("the other steps are matched above"),
                    }
                }
            };
            stack.push(x);
        }
        let value = stack.pop()?;
        stack.is_empty().then_some((value, uses_time))
    }
}

/// The expressions of a `REPEAT`'s body read so far, each by where its first token starts in
/// the scene text, so that each is read from its text once and computed again at each
/// iteration. Only what does not depend on the names' values is kept: a name's value is looked
/// up at each computation (a `LET` of the body, the loop variable), and a computation that
/// fails is read again from the text, so errors are the reader's own.
#[derive(Debug, Default)]
pub(super) struct Tapes {
    by_start: HashMap<usize, Tape, std::hash::BuildHasherDefault<NameHasher>>,
    stack: Vec<f64>,
}

impl Tapes {
    /// The value of the expression whose first token starts at byte `start`, if it was kept
    /// and computes without failing: its value, whether it depended on the time, its span and
    /// the token after it.
    pub(super) fn eval(
        &mut self,
        start: usize,
        text: &str,
        names: &Names,
    ) -> Option<(f64, bool, Span, usize)> {
        let tape = self.by_start.get(&start)?;
        let (value, uses_time) = tape.eval(text, names, &mut self.stack)?;
        Some((value, uses_time, tape.span.clone(), tape.next_token))
    }

    /// Keeps the steps of the expression whose first token starts at byte `start`.
    pub(super) fn keep(&mut self, start: usize, tape: Tape) {
        self.by_start.insert(start, tape);
    }
}

/// True when the word at `line.pos`, a number as written, is followed by an operator that
/// continues it into an expression (so it cannot be read as a lone number). Looks at the
/// next token only.
pub(super) fn continues(line: &Line) -> bool {
    let Some(next) = line
        .tokens
        .get(line.pos + 1)
        .filter(|t| t.kind == TokenKind::Word)
    else {
        return false;
    };
    let text = line.text;
    let Some((tk, span)) = split_word(text, next.span.clone()).next() else {
        return false;
    };
    match tk {
        Tk::Star | Tk::Slash | Tk::Caret => true,
        // `1 - 2` and `1 -(2)`: see the space rule in the module documentation.
        Tk::Plus | Tk::Minus => text[span.end..]
            .chars()
            .next()
            .is_none_or(char::is_whitespace),
        _ => false,
    }
}

/// An expression read: its value, its span and the index of the token after it.
pub(super) struct Read {
    /// The value (finite).
    pub(super) value: f64,
    /// Where it is written.
    pub(super) span: Span,
    /// The token after it.
    pub(super) next_token: usize,
    /// Its steps, to compute it again with other values of its names.
    pub(super) tape: Tape,
}

/// Reads the expression at `line.pos` in a list of values. `Ok(None)` when the line is not at
/// an expression (the caller reports what it expected); with it, whether what was read
/// depended on the time (so that an error can name the frame).
pub(super) fn read(line: &Line) -> (Result<Option<Read>, Fail>, bool) {
    let mut reader = Reader {
        text: line.text,
        names: line.names,
        pieces: pieces(line),
        at: 0,
        parens: 0,
        depth: 0,
        list: true,
        uses_time: false,
        tape: Vec::new(),
    };
    if !looks_like_expression(&reader) {
        return (Ok(None), false);
    }
    match finish(&mut reader) {
        Ok((value, span, next_token)) => {
            let tape = Tape {
                ops: std::mem::take(&mut reader.tape),
                span: span.clone(),
                next_token,
            };
            (
                Ok(Some(Read {
                    value,
                    span,
                    next_token,
                    tape,
                })),
                reader.uses_time,
            )
        }
        Err(Fail::NotAnExpression) => (Ok(None), false),
        Err(fail) => (Err(fail), reader.uses_time),
    }
}

/// False when the first word is not written as an expression at all (`one`, `1.2.3`, `2x`,
/// `a#b`, an unknown name alone) or a vector starts here: the caller's "expected a number"
/// says more than an expression error would.
fn looks_like_expression(reader: &Reader) -> bool {
    let Some(first) = reader.pieces.first() else {
        return false;
    };
    // The pieces of the first word: a prefix of `pieces`, nothing allocated.
    let word = &reader.pieces[..reader
        .pieces
        .iter()
        .take_while(|p| p.token == first.token)
        .count()];
    let operand = |p: &Piece| matches!(p.tk, Tk::Num | Tk::Name);
    let has_operator = word.iter().any(|p| !operand(p));
    if word.iter().any(|p| p.tk == Tk::Bad)
        || (!has_operator && word.windows(2).any(|w| operand(&w[0]) && operand(&w[1])))
    {
        return false;
    }
    if first.tk == Tk::Name && first.last {
        let name = reader.piece_text(first);
        let is_function = FUNCTIONS.iter().any(|f| f.0 == name);
        return is_function || reader.names.value(name).is_some();
    }
    if first.tk == Tk::Open {
        // `(a, b, c)`: a comma at the first level of these parentheses.
        let mut depth = 0usize;
        for p in &reader.pieces {
            match p.tk {
                Tk::Open => depth += 1,
                Tk::Close if depth <= 1 => break,
                Tk::Close => depth -= 1,
                Tk::Comma if depth == 1 => return false,
                _ => {}
            }
        }
    }
    true
}

/// Reads an expression from the reader's first piece to the end of a token; returns its
/// value, its span and the index of the next lexer token.
fn finish(reader: &mut Reader) -> Result<(f64, Span, usize), Fail> {
    match reader.peek_tk() {
        Some(Tk::Num | Tk::Name | Tk::Plus | Tk::Minus | Tk::Open) => {}
        _ => return Err(Fail::NotAnExpression),
    }
    let (x, span) = reader.sum()?;
    let last = &reader.pieces[reader.at - 1];
    if !last.last {
        let next = reader.here();
        return Err(syntax(
            next,
            format!(
                "unexpected {} after `{}`: is an operator missing?",
                reader.found(),
                shorten(&reader.text[span.clone()], 30)
            ),
            "expected an operator or a space",
        ));
    }
    Ok((x, span, last.token + 1))
}

/// A `LET` definition read: the name and where it is written, its value, whether the value
/// depends on the time, and the token after the expression.
pub(super) struct LetDefinition {
    pub(super) name: String,
    pub(super) name_span: Span,
    pub(super) value: f64,
    pub(super) uses_time: bool,
    pub(super) next_token: usize,
}

/// Why a `LET` could not be read.
pub(super) enum LetFail {
    /// Something else than `what` at token `at` ("expected …, found …").
    Expected { what: String, at: usize },
    /// A mistake at `span`.
    At {
        span: Span,
        message: String,
        label: String,
    },
    /// The value, read as `what`, failed.
    Expression { what: String, fail: Fail },
}

/// Reads `name = expression` from `line.pos` (after the `LET` keyword); with it, whether the
/// value's expression depended on the time.
pub(super) fn read_let(line: &Line) -> (Result<LetDefinition, LetFail>, bool) {
    let ps = pieces(line);
    let at = |span: Span, message: String, label: &str| {
        Err(LetFail::At {
            span,
            message,
            label: label.into(),
        })
    };
    let Some(name_piece) = ps.first().filter(|p| p.tk == Tk::Name) else {
        let what = "a name (letters, digits and `_`, starting with a letter)".into();
        let fail = LetFail::Expected { what, at: line.pos };
        return (Err(fail), false);
    };
    let name = line.text[name_piece.span.clone()].to_string();
    let name_span = name_piece.span.clone();
    if !name_piece.last && ps.get(1).is_some_and(|p| p.tk != Tk::Equals) {
        let p = &ps[1];
        let word = &line.text[line.tokens[name_piece.token].span.clone()];
        let message = format!(
            "`{}` is not a valid name: names contain only letters, digits and `_`",
            shorten(word, 30)
        );
        return (
            at(name_span.start..p.span.end, message, "invalid name"),
            false,
        );
    }
    if is_reserved(&name) {
        let message = format!(
            "`{name}` is a built-in name and cannot be defined by LET{}",
            if name.eq_ignore_ascii_case("pi") {
                " (it is already π: remove this line)"
            } else {
                ""
            }
        );
        return (at(name_span, message, "reserved name"), false);
    }
    if let Some(d) = line.names.lets.get(&name) {
        let message = format!("`{name}` is already defined on line {}", d.line);
        return (at(name_span, message, "defined twice"), false);
    }
    match ps.get(1) {
        Some(p) if p.tk == Tk::Equals => {}
        Some(p) => {
            let message = format!(
                "expected `=` after the name, found `{}`",
                shorten(&line.text[p.span.clone()], 30)
            );
            return (at(p.span.clone(), message, "expected `=`"), false);
        }
        None => {
            let message = "expected `=` after the name, found end of line".into();
            return (
                at(name_span.end..name_span.end, message, "expected `=`"),
                false,
            );
        }
    }
    let mut reader = Reader {
        text: line.text,
        names: line.names,
        pieces: ps[2..].to_vec(),
        at: 0,
        parens: 0,
        depth: 0,
        list: false,
        uses_time: false,
        tape: Vec::new(),
    };
    let what = format!("the value of {name}");
    let result = match finish(&mut reader) {
        Ok((value, _, next_token)) => Ok(LetDefinition {
            name,
            name_span,
            value,
            uses_time: reader.uses_time,
            next_token,
        }),
        Err(Fail::NotAnExpression) => Err(LetFail::Expected {
            what: format!("{what} (an expression)"),
            at: ps.get(2).map_or(line.tokens.len(), |p| p.token),
        }),
        Err(fail) => Err(LetFail::Expression { what, fail }),
    };
    (result, reader.uses_time)
}

/// Records a `LET` definition read on `line`.
pub(super) fn define(names: &mut Names, name: String, value: f64, uses_time: bool, line: usize) {
    names.lets.insert(
        name,
        Defined {
            value,
            line,
            uses_time,
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::lexer::lex_line;

    /// A failure's message, as the statement reader would start it.
    fn message(fail: Fail) -> String {
        match fail {
            Fail::NotAnExpression => "not an expression".into(),
            Fail::Syntax { message, .. } | Fail::Value { message, .. } => message,
        }
    }

    /// Reads `text` as one expression in a list (as a number argument is read) at `time`.
    fn eval_at(text: &str, time: Option<FrameTime>, lets: &[(&str, f64)]) -> Result<f64, String> {
        let mut names = Names::new(time);
        for (n, v) in lets {
            define(&mut names, n.to_string(), *v, false, 1);
        }
        let tokens = lex_line(text, 0, text.len()).unwrap();
        let line = Line {
            text,
            tokens: &tokens,
            pos: 0,
            names: &names,
        };
        match read(&line).0 {
            Ok(Some(r)) if r.next_token == tokens.len() => Ok(r.value),
            Ok(Some(r)) => Err(format!("stopped at token {}", r.next_token)),
            Ok(None) => Err("not an expression".into()),
            Err(fail) => Err(message(fail)),
        }
    }

    fn eval(text: &str) -> f64 {
        eval_at(text, None, &[]).unwrap_or_else(|e| panic!("{text}: {e}"))
    }

    #[test]
    fn arithmetic_against_hand_computed_values() {
        assert_eq!(eval("1 + 2 * 3"), 7.0);
        assert_eq!(eval("(1 + 2) * 3"), 9.0);
        assert_eq!(eval("2^3^2"), 512.0); // right associative: 2^(3^2)
        assert_eq!(eval("-2^2"), -4.0); // the power binds tighter than the sign
        assert_eq!(eval("(-2)^2"), 4.0);
        assert_eq!(eval("10 / 4 - 1"), 1.5);
        assert_eq!(eval("1-2-3"), -4.0); // left associative
        assert_eq!(eval("8/2/2"), 2.0);
        assert_eq!(eval("2*-3"), -6.0);
        assert_eq!(eval("--3"), 3.0);
        assert_eq!(eval("1e3 + 2.5E-1"), 1000.25);
        assert_eq!(eval("+.5"), 0.5);
        assert_eq!(eval("4^-0.5"), 0.5);
    }

    #[test]
    fn functions_take_radians() {
        assert!((eval("sin(pi/6)") - 0.5).abs() < 1e-15);
        assert_eq!(eval("cos(PI)"), -1.0);
        assert_eq!(eval("cbrt(-27)"), -3.0);
        assert_eq!(eval("exp(0) + log(1)"), 1.0);
        assert!((eval("cos(pi)") + 1.0).abs() < 1e-15);
        assert!((eval("tan(pi/4)") - 1.0).abs() < 1e-15);
        assert_eq!(eval("sqrt(16)"), 4.0);
        assert_eq!(eval("abs(-2.5)"), 2.5);
        assert_eq!(eval("min(3, 1, 2)"), 1.0);
        assert_eq!(eval("max(3, 1 + 4, 2)"), 5.0);
        assert_eq!(eval("max(1 -2, 0)"), 0.0); // inside parentheses, `-` is an operator
        assert_eq!(eval("2*sqrt(9)^2"), 18.0);
    }

    #[test]
    fn time_and_names() {
        let t = |frame, count| Some(FrameTime { frame, count });
        assert_eq!(eval_at("clock", t(0, 5), &[]), Ok(0.0));
        assert_eq!(eval_at("clock", t(1, 5), &[]), Ok(0.25));
        assert_eq!(eval_at("clock", t(4, 5), &[]), Ok(1.0));
        assert_eq!(eval_at("clock", t(0, 1), &[]), Ok(0.0));
        assert_eq!(eval_at("frame * 2 + frames", t(3, 10), &[]), Ok(16.0));
        assert_eq!(eval_at("clock", None, &[]), Ok(0.0));
        assert_eq!(
            eval_at("0.8 + 0.6*clock", t(2, 3), &[]),
            Ok(0.8 + 0.6 * 1.0)
        );
        assert_eq!(eval_at("2*mu + 1", None, &[("mu", 0.25)]), Ok(1.5));
        assert_eq!(eval_at("mu_2^2", None, &[("mu_2", 3.0)]), Ok(9.0));
    }

    #[test]
    fn value_errors_say_what_went_wrong() {
        let t = Some(FrameTime { frame: 2, count: 3 });
        let e = eval_at("1 / (clock - 1)", t, &[]).unwrap_err();
        assert!(e.contains("division by zero: `(clock - 1)` is 0"), "{e}");
        let e = eval_at("sqrt(0.5 - clock)", t, &[]).unwrap_err();
        assert!(e.contains("sqrt of a negative number (-0.5)"), "{e}");
        let e = eval_at("(-8)^(1/3)", None, &[]).unwrap_err();
        assert!(e.contains("is not a real number"), "{e}");
        let e = eval_at("0^-1", None, &[]).unwrap_err();
        assert!(e.contains("division by zero"), "{e}");
        let e = eval_at("10^400", None, &[]).unwrap_err();
        assert!(e.contains("overflows"), "{e}");
        let e = eval_at("2 * 1e999", None, &[]).unwrap_err();
        assert!(e.contains("overflows"), "{e}");
    }

    #[test]
    fn syntax_errors() {
        let e = eval_at("1 + mu", None, &[]).unwrap_err();
        assert!(e.contains("unknown name `mu`"), "{e}");
        let e = eval_at("sin 1", None, &[]).unwrap_err();
        assert!(e.contains("`sin` is a function"), "{e}");
        let e = eval_at("min(1)", None, &[]).unwrap_err();
        assert!(e.contains("min takes at least 2 arguments, not 1"), "{e}");
        let e = eval_at("sqrt(1, 2)", None, &[]).unwrap_err();
        assert!(e.contains("sqrt takes one argument, not 2"), "{e}");
        let e = eval_at("(1 + 2", None, &[]).unwrap_err();
        assert!(e.contains("expected an operator or `)`"), "{e}");
        let e = eval_at("1 + ", None, &[]).unwrap_err();
        assert!(e.contains("ends too early"), "{e}");
        let deep = format!("{}1{}", "(".repeat(150), ")".repeat(150));
        let e = eval_at(&deep, None, &[]).unwrap_err();
        assert!(e.contains("nested too deeply"), "{e}");
        // Not expressions at all: the caller says what it expected.
        assert_eq!(eval_at("one", None, &[]), Err("not an expression".into()));
        assert_eq!(eval_at("1.2.3", None, &[]), Err("not an expression".into()));
        assert_eq!(
            eval_at("(1, 2)", None, &[]),
            Err("not an expression".into())
        );
    }

    #[test]
    fn a_sign_after_a_space_starts_the_next_value() {
        let text = "1 -2 3-1 4 - 1 (5)";
        let names = Names::new(None);
        let tokens = lex_line(text, 0, text.len()).unwrap();
        let mut line = Line {
            text,
            tokens: &tokens,
            pos: 0,
            names: &names,
        };
        let mut values = Vec::new();
        while line.pos < tokens.len() {
            match read(&line).0.ok().flatten() {
                Some(r) => {
                    values.push(r.value);
                    line.pos = r.next_token;
                }
                None => break,
            }
        }
        assert_eq!(values, vec![1.0, -2.0, 2.0, 3.0, 5.0]);
    }

    #[test]
    fn frame_note_names_the_frame() {
        let names = Names::new(Some(FrameTime {
            frame: 3,
            count: 10,
        }));
        assert_eq!(names.frame_note(), " (at frame 3 of 0..=9, clock = 0.3333)");
        assert_eq!(Names::new(None).frame_note(), "");
    }
}
