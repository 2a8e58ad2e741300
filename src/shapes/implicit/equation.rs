//! The equation language: lexer and recursive-descent parser producing a syntax tree with
//! byte spans, so every later error can point at the text it is about.
//!
//! Grammar (`x`, `y`, `z` also in upper case; juxtaposition multiplies, so `2x y` = `2*x*y`):
//!
//! ```text
//! equation := sum [ '=' sum ]
//! sum      := term { ('+' | '-') term }
//! term     := unary { ['*' | '/'] unary }          (no operator: implicit '*')
//! unary    := '-' unary | '+' unary | power
//! power    := primary [ '^' unary ]                (right associative: x^2^3 = x^(2^3))
//! primary  := number | 'x' | 'y' | 'z' | '(' sum ')'
//! number   := digits ['.' digits] [('e'|'E') ['+'|'-'] digits]   (or '.' digits …)
//! ```

use super::coef::Coef;
use super::EquationError;

/// A byte range `[start, end)` of the equation text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// First byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    fn to(self, other: Span) -> Span {
        Span {
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }

    /// An error pointing at this span (at least one byte wide where the text allows).
    pub fn error(self, message: impl Into<String>) -> EquationError {
        EquationError {
            offset: self.start,
            len: (self.end - self.start).max(1),
            message: message.into(),
        }
    }
}

/// A syntax-tree node. Sums and products are n-ary (flat lists), so long chains of terms
/// never make the tree deep; nesting (parentheses, unary minus, powers) is limited to
/// [`MAX_NESTING`] levels.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    /// A number as written.
    Num(Coef),
    /// A variable: 0 = x, 1 = y, 2 = z.
    Var(usize),
    /// `-a`.
    Neg(Box<Expr>),
    /// `±a ± b ± …`: each term with `true` when it is subtracted (also `lhs = rhs`).
    Sum(Vec<(bool, Expr)>),
    /// `a * b / c …`: each factor with `true` when it divides.
    Product(Vec<(bool, Expr)>),
    /// `a ^ b`.
    Pow(Box<Expr>, Box<Expr>),
}

/// Deepest nesting of parentheses, unary signs and powers accepted.
pub const MAX_NESTING: usize = 200;

/// A node with the span of text it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// What it is.
    pub node: Node,
    /// Where it is.
    pub span: Span,
}

impl Expr {
    /// Direct floating-point evaluation at `p = [x, y, z]`, without expansion (the reference
    /// the expanded polynomial is tested against).
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        match &self.node {
            Node::Num(c) => c.to_f64(),
            Node::Var(i) => p[*i],
            Node::Neg(a) => -a.eval(p),
            Node::Sum(terms) => terms
                .iter()
                .map(|(minus, t)| if *minus { -t.eval(p) } else { t.eval(p) })
                .sum(),
            Node::Product(factors) => factors.iter().fold(1.0, |acc, (div, f)| {
                if *div {
                    acc / f.eval(p)
                } else {
                    acc * f.eval(p)
                }
            }),
            Node::Pow(a, b) => a.eval(p).powi(b.eval(p) as i32),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Tok {
    Num(Coef),
    Ident,
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    Equals,
    End,
}

struct Lexer<'a> {
    text: &'a str,
    toks: Vec<(Tok, Span)>,
}

impl<'a> Lexer<'a> {
    fn run(text: &'a str) -> Result<Vec<(Tok, Span)>, EquationError> {
        let mut lx = Lexer {
            text,
            toks: Vec::new(),
        };
        let bytes = text.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            let start = i;
            let single = match c {
                b'+' => Some(Tok::Plus),
                b'-' => Some(Tok::Minus),
                b'*' => Some(Tok::Star),
                b'/' => Some(Tok::Slash),
                b'^' => Some(Tok::Caret),
                b'(' => Some(Tok::LParen),
                b')' => Some(Tok::RParen),
                b'=' => Some(Tok::Equals),
                _ => None,
            };
            if let Some(t) = single {
                lx.push(t, start, start + 1);
                i += 1;
            } else if c.is_ascii_whitespace() {
                i += 1;
            } else if c.is_ascii_digit() || c == b'.' {
                i = lx.number(start)?;
            } else if c.is_ascii_alphabetic() || c == b'_' {
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                lx.push(Tok::Ident, start, i);
            } else {
                let ch = text[start..].chars().next().unwrap_or('?');
                let hint = match ch {
                    '−' | '–' => " (use the ASCII '-')",
                    '×' | '·' => " (use '*')",
                    '²' | '³' => " (write powers as x^2)",
                    _ => "",
                };
                return Err(Span {
                    start,
                    end: start + ch.len_utf8(),
                }
                .error(format!("unexpected character '{ch}'{hint}")));
            }
        }
        lx.push(Tok::End, text.len(), text.len());
        Ok(lx.toks)
    }

    fn push(&mut self, t: Tok, start: usize, end: usize) {
        self.toks.push((t, Span { start, end }));
    }

    fn number(&mut self, start: usize) -> Result<usize, EquationError> {
        let b = self.text.as_bytes();
        let digits = |mut i: usize| {
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            i
        };
        let mut i = digits(start);
        let int_digits = i - start;
        let mut frac_digits = 0;
        if i < b.len() && b[i] == b'.' {
            let j = digits(i + 1);
            frac_digits = j - i - 1;
            i = j;
        }
        if int_digits + frac_digits == 0 {
            return Err(Span {
                start,
                end: start + 1,
            }
            .error("a '.' must be part of a number such as 0.5"));
        }
        // An exponent only when digits follow: "2e" is not a number.
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            let mut j = i + 1;
            if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                j += 1;
            }
            let k = digits(j);
            if k > j {
                i = k;
            }
        }
        let span = Span { start, end: i };
        let value = Coef::parse_decimal(&self.text[start..i])
            .ok_or_else(|| span.error("this number is out of range"))?;
        self.toks.push((Tok::Num(value), span));
        Ok(i)
    }
}

/// Values of named constants an equation may use besides x, y and z (`None`: not a name).
pub type Constants<'a> = &'a dyn Fn(&str) -> Option<f64>;

struct Parser<'a> {
    text: &'a str,
    constants: Constants<'a>,
    toks: Vec<(Tok, Span)>,
    pos: usize,
    depth: usize,
}

/// Parses an equation into a syntax tree for `lhs − rhs` (or just `lhs`).
pub fn parse(text: &str) -> Result<Expr, EquationError> {
    parse_with(text, &|_| None)
}

/// As [`parse`], where a name other than x, y and z stands for its value in `constants`
/// (the exact decimal Rust prints for it, so `mu` = 0.8 reads as `0.8` would).
pub fn parse_with(text: &str, constants: Constants) -> Result<Expr, EquationError> {
    let toks = Lexer::run(text)?;
    let mut p = Parser {
        text,
        constants,
        toks,
        pos: 0,
        depth: 0,
    };
    if p.peek().0 == Tok::End {
        return Err(Span {
            start: 0,
            end: text.len(),
        }
        .error(
            "the equation is empty: write a polynomial in x, y and z, such as x^2 + y^2 + z^2 = 1",
        ));
    }
    let lhs = p.sum()?;
    let expr = if p.peek().0 == Tok::Equals {
        let eq_span = p.next().1;
        if p.peek().0 == Tok::End {
            return Err(p.peek().1.error("expected an expression after '='"));
        }
        let rhs = p.sum()?;
        let span = lhs.span.to(rhs.span);
        let _ = eq_span;
        Expr {
            node: Node::Sum(vec![(false, lhs), (true, rhs)]),
            span,
        }
    } else {
        lhs
    };
    let (tok, span) = p.peek();
    match tok {
        Tok::End => Ok(expr),
        Tok::RParen => Err(span.error("unmatched ')': there is no '(' before it to close")),
        Tok::Equals => Err(span.error("only one '=' is allowed in an equation")),
        _ => Err(span.error("unexpected text after the equation")),
    }
}

/// A named constant's value as a number node (negative values as a negated number).
fn constant(value: f64, span: Span) -> Result<Expr, EquationError> {
    let magnitude = Coef::parse_decimal(&format!("{}", value.abs()))
        .ok_or_else(|| span.error(format!("the value {value} is not a finite number")))?;
    let num = Expr {
        node: Node::Num(magnitude),
        span,
    };
    Ok(if value.is_sign_negative() {
        Expr {
            node: Node::Neg(Box::new(num)),
            span,
        }
    } else {
        num
    })
}

impl Parser<'_> {
    fn peek(&self) -> (Tok, Span) {
        self.toks[self.pos]
    }

    fn next(&mut self) -> (Tok, Span) {
        let t = self.toks[self.pos];
        if t.0 != Tok::End {
            self.pos += 1;
        }
        t
    }

    fn sum(&mut self) -> Result<Expr, EquationError> {
        let first = self.term()?;
        let mut span = first.span;
        let mut terms = vec![(false, first)];
        loop {
            let op = self.peek().0;
            if op != Tok::Plus && op != Tok::Minus {
                break;
            }
            self.next();
            let t = self.term()?;
            span = span.to(t.span);
            terms.push((op == Tok::Minus, t));
        }
        Ok(if terms.len() == 1 {
            terms.pop().map(|(_, t)| t).expect("one term")
        } else {
            Expr {
                node: Node::Sum(terms),
                span,
            }
        })
    }

    fn starts_primary(t: Tok) -> bool {
        matches!(t, Tok::Num(_) | Tok::Ident | Tok::LParen)
    }

    fn term(&mut self) -> Result<Expr, EquationError> {
        let first = self.unary()?;
        let mut span = first.span;
        let mut factors = vec![(false, first)];
        loop {
            let op = self.peek().0;
            let div = match op {
                Tok::Star => false,
                Tok::Slash => true,
                t if Self::starts_primary(t) => false,
                _ => break,
            };
            if matches!(op, Tok::Star | Tok::Slash) {
                self.next();
            }
            let f = self.unary()?;
            span = span.to(f.span);
            factors.push((div, f));
        }
        Ok(if factors.len() == 1 {
            factors.pop().map(|(_, f)| f).expect("one factor")
        } else {
            Expr {
                node: Node::Product(factors),
                span,
            }
        })
    }

    /// Enters one level of nesting, or fails past [`MAX_NESTING`].
    fn deeper(&mut self, span: Span) -> Result<(), EquationError> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(span.error(format!(
                "the equation is nested too deeply (more than {MAX_NESTING} levels of parentheses, signs or powers)"
            )));
        }
        Ok(())
    }

    fn unary(&mut self) -> Result<Expr, EquationError> {
        self.deeper(self.peek().1)?;
        let r = self.unary_inner();
        self.depth -= 1;
        r
    }

    fn unary_inner(&mut self) -> Result<Expr, EquationError> {
        match self.peek() {
            (Tok::Minus, span) => {
                self.next();
                let a = self.unary()?;
                let span = span.to(a.span);
                Ok(Expr {
                    node: Node::Neg(Box::new(a)),
                    span,
                })
            }
            (Tok::Plus, _) => {
                self.next();
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Expr, EquationError> {
        let base = self.primary()?;
        if self.peek().0 != Tok::Caret {
            return Ok(base);
        }
        self.next();
        let exp = self.unary()?;
        let span = base.span.to(exp.span);
        Ok(Expr {
            node: Node::Pow(Box::new(base), Box::new(exp)),
            span,
        })
    }

    fn primary(&mut self) -> Result<Expr, EquationError> {
        let (tok, span) = self.next();
        match tok {
            Tok::Num(c) => Ok(Expr {
                node: Node::Num(c),
                span,
            }),
            Tok::Ident => {
                let name = &self.text[span.start..span.end];
                let var = match name {
                    "x" | "X" => Some(0),
                    "y" | "Y" => Some(1),
                    "z" | "Z" => Some(2),
                    _ => None,
                };
                if let Some(v) = var {
                    return Ok(Expr {
                        node: Node::Var(v),
                        span,
                    });
                }
                if let Some(value) = (self.constants)(name) {
                    return constant(value, span);
                }
                if self.peek().0 == Tok::LParen {
                    Err(span.error(format!(
                        "unknown function '{name}': only polynomials are allowed (+, -, *, / by a constant, ^ with a whole-number exponent)"
                    )))
                } else {
                    Err(span.error(format!(
                        "unknown variable '{name}': the variables are x, y and z (write products as x*y)"
                    )))
                }
            }
            Tok::LParen => {
                if self.peek().0 == Tok::RParen {
                    return Err(span.to(self.peek().1).error("empty parentheses"));
                }
                let inner = self.sum()?;
                match self.peek() {
                    (Tok::RParen, close) => {
                        self.next();
                        Ok(Expr {
                            node: inner.node,
                            span: span.to(close),
                        })
                    }
                    _ => Err(span.error("unbalanced parentheses: this '(' is never closed")),
                }
            }
            Tok::End => {
                Err(span.error("the equation ends too early: expected a number, x, y, z or '('"))
            }
            Tok::RParen => Err(span.error("unmatched ')': expected a number, x, y, z or '(' here")),
            Tok::Equals => Err(span.error("expected an expression before '='")),
            _ => Err(span.error(format!(
                "expected a number, x, y, z or '(' here, not '{}'",
                &self.text[span.start..span.end]
            ))),
        }
    }
}
