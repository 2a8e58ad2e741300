//! The equation language: lexer and recursive-descent parser producing a syntax tree with
//! byte spans, so every later error can point at the text it is about.
//!
//! Grammar (`x`, `y`, `z` also in upper case; juxtaposition multiplies, so `2x y` = `2*x*y`):
//!
//! ```text
//! equation := sum [ '=' sum ] [ ';' ]
//! sum      := term { ('+' | '-') term }
//! term     := unary { ['*' | '/'] unary }          (no operator: implicit '*')
//! unary    := '-' unary | '+' unary | power
//! power    := primary [ ('^' | '**') unary ]       (right associative: x^2^3 = x^(2^3))
//! primary  := number | 'x' | 'y' | 'z' | 'pi' | function '(' sum ')' | '(' sum ')'
//! function := 'sqrt' | 'cbrt' | 'sin' | 'cos' | 'tan' | 'exp' | 'log'
//! number   := digits ['.' digits] [('e'|'E') ['+'|'-'] digits]   (or '.' digits …)
//! ```
//!
//! `pi` (any case) is π unless the caller's constants name it. Functions, and powers with a
//! negative or non-whole exponent, are folded to numbers when expanded ([`super::poly`]); they
//! may hold no x, y or z.

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
    /// `f(a)`, a function of a constant.
    Call(Function, Box<Expr>),
}

/// A function an equation may apply to a constant (angles in radians, `log` natural).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Function {
    /// Square root of a value ≥ 0.
    Sqrt,
    /// Real cube root (of any sign).
    Cbrt,
    /// Sine.
    Sin,
    /// Cosine.
    Cos,
    /// Tangent.
    Tan,
    /// e to the power.
    Exp,
    /// Natural logarithm of a value > 0.
    Log,
}

impl Function {
    /// Every function with the name it is written by.
    pub const ALL: [(&'static str, Function); 7] = [
        ("sqrt", Function::Sqrt),
        ("cbrt", Function::Cbrt),
        ("sin", Function::Sin),
        ("cos", Function::Cos),
        ("tan", Function::Tan),
        ("exp", Function::Exp),
        ("log", Function::Log),
    ];

    /// The function written `name` (lower case, or `ln` for `log`).
    pub fn named(name: &str) -> Option<Function> {
        if name == "ln" {
            return Some(Function::Log);
        }
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
    }

    /// Its name as written.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, f)| *f == self)
            .map(|(n, _)| *n)
            .expect("every function is named")
    }

    /// `f(a)`, or why it has no real value.
    pub fn apply(self, a: f64) -> Result<f64, String> {
        let v = match self {
            Function::Sqrt if a < 0.0 => {
                return Err(format!("sqrt of a negative number ({a})"));
            }
            Function::Log if a <= 0.0 => {
                return Err(format!("log of a number that is not positive ({a})"));
            }
            Function::Sqrt => a.sqrt(),
            Function::Cbrt => a.cbrt(),
            Function::Sin => a.sin(),
            Function::Cos => a.cos(),
            Function::Tan => a.tan(),
            Function::Exp => a.exp(),
            Function::Log => a.ln(),
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("{}({a}) is not a finite number", self.name()))
        }
    }
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
            Node::Pow(a, b) => {
                let e = b.eval(p);
                if e.fract() == 0.0 && e.abs() <= f64::from(i32::MAX) {
                    a.eval(p).powi(e as i32)
                } else {
                    a.eval(p).powf(e)
                }
            }
            Node::Call(f, a) => f.apply(a.eval(p)).unwrap_or(f64::NAN),
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
                b'*' if bytes.get(i + 1) == Some(&b'*') => {
                    lx.push(Tok::Caret, start, start + 2);
                    i += 2;
                    continue;
                }
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
            } else if c == b';' {
                // A trailing ';' (as surf and SURFER users end a statement) ends the equation.
                if text[i..]
                    .trim_start_matches([';', ' ', '\t', '\r', '\n'])
                    .is_empty()
                {
                    break;
                }
                return Err(Span {
                    start,
                    end: start + 1,
                }
                .error("';' ends the equation: nothing may follow it (write one equation)"));
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

/// The error for a function the language lacks, with what to write instead.
fn unknown_function(name: &str) -> String {
    let names: Vec<&str> = Function::ALL.iter().map(|(n, _)| *n).collect();
    let instead = match name.to_ascii_lowercase().as_str() {
        "abs" => " (abs is not a polynomial: for abs(p) = c write p^2 = c^2)",
        "pow" => " (write a^b)",
        "sqr" => " (write a^2)",
        "exp2" | "log2" | "log10" => " (write the power or divide by log(2) or log(10))",
        _ => "",
    };
    format!(
        "unknown function '{name}'{instead}: an equation is a polynomial in x, y and z; \
         only constants may go inside the functions {}",
        names.join(", ")
    )
}

impl Parser<'_> {
    /// `f ( sum )`, after the name: the argument may not be empty.
    fn call(&mut self, f: Function, name: Span) -> Result<Expr, EquationError> {
        let open = self.next().1;
        self.deeper(open)?;
        let r = self.call_inner(f, name, open);
        self.depth -= 1;
        r
    }

    fn call_inner(&mut self, f: Function, name: Span, open: Span) -> Result<Expr, EquationError> {
        if self.peek().0 == Tok::RParen {
            return Err(open.to(self.peek().1).error(format!(
                "{} needs a value: {}(2)",
                f.name(),
                f.name()
            )));
        }
        let arg = self.sum()?;
        match self.peek() {
            (Tok::RParen, close) => {
                self.next();
                Ok(Expr {
                    node: Node::Call(f, Box::new(arg)),
                    span: name.to(close),
                })
            }
            _ => Err(open.error("unbalanced parentheses: this '(' is never closed")),
        }
    }

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
                if name.eq_ignore_ascii_case("pi") {
                    return constant(std::f64::consts::PI, span);
                }
                if self.peek().0 == Tok::LParen {
                    if let Some(f) = Function::named(&name.to_ascii_lowercase()) {
                        return self.call(f, span);
                    }
                    Err(span.error(unknown_function(name)))
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

#[cfg(test)]
mod tests {
    use super::super::{expand, expand_with};

    /// The expanded polynomial's coefficient of `xⁱ yʲ zᵏ` as an `f64`.
    fn coefficient(equation: &str, exps: [u8; 3]) -> f64 {
        let p = expand(equation).unwrap_or_else(|e| panic!("{equation}: {}", e.message));
        p.terms.get(&exps).map_or(0.0, |c| c.to_f64())
    }

    fn error(equation: &str) -> String {
        match expand(equation) {
            Ok(_) => panic!("{equation} was accepted"),
            Err(e) => e.message,
        }
    }

    #[test]
    fn functions_of_constants_are_folded() {
        let cases: [(&str, f64); 9] = [
            ("sqrt(2)*x", 2f64.sqrt()),
            ("sqrt(5 - sqrt(5))*x", (5.0 - 5f64.sqrt()).sqrt()),
            ("cbrt(-8)*x", -2.0),
            ("sin(1)*x", 1f64.sin()),
            ("cos(2*PI/5)*x", (2.0 * std::f64::consts::PI / 5.0).cos()),
            ("tan(0.5)*x", 0.5f64.tan()),
            ("exp(1)*x", std::f64::consts::E),
            ("log(10)*x", 10f64.ln()),
            ("SQRT(9) x", 3.0),
        ];
        for (eq, want) in cases {
            let got = coefficient(eq, [1, 0, 0]);
            assert!(
                (got - want).abs() <= 1e-15 * want.abs(),
                "{eq}: {got} vs {want}"
            );
        }
        // A folded whole number stays exact: sqrt(4)^2 is 4, not 4.000…1.
        assert_eq!(coefficient("sqrt(4)^2*x", [1, 0, 0]), 4.0);
    }

    #[test]
    fn powers_of_constants_may_be_negative_or_not_whole() {
        assert_eq!(coefficient("2^(1/2)*x", [1, 0, 0]), 2f64.sqrt());
        assert_eq!(coefficient("(1/4)^-1*x", [1, 0, 0]), 4.0);
        assert_eq!(coefficient("2^-2*x", [1, 0, 0]), 0.25);
        assert_eq!(coefficient("x**2 + 2**3", [0, 0, 0]), 8.0);
        assert_eq!(coefficient("x**2 + 2**3", [2, 0, 0]), 1.0);
    }

    #[test]
    fn pi_in_any_case_is_pi_unless_a_constant_names_it() {
        for eq in ["pi*x", "PI*x", "Pi x", "2*pi/2*x"] {
            assert_eq!(coefficient(eq, [1, 0, 0]), std::f64::consts::PI, "{eq}");
        }
        let p = expand_with("pi*x", &|n| (n == "pi").then_some(3.0)).expect("accepted");
        assert_eq!(p.terms[&[1, 0, 0]].to_f64(), 3.0);
    }

    #[test]
    fn a_trailing_semicolon_ends_the_equation() {
        assert_eq!(coefficient("x^2 + y^2 - 1;", [0, 0, 0]), -1.0);
        assert_eq!(coefficient("x^2 + y^2 - 1 ; ;\n", [2, 0, 0]), 1.0);
        assert!(error("x^2; y").contains("nothing may follow"));
    }

    #[test]
    fn what_stays_unsupported_says_what_to_write() {
        let e = error("sqrt(x) - 1");
        assert!(e.contains("only constants may go inside"), "{e}");
        let e = error("x^(1/2) - 1");
        assert!(e.contains("raise both sides"), "{e}");
        let e = error("x^-1 - 1");
        assert!(e.contains("multiply both sides"), "{e}");
        let e = error("abs(x) - 1");
        assert!(e.contains("p^2 = c^2"), "{e}");
        let e = error("sqrt(-2)*x");
        assert!(e.contains("negative"), "{e}");
        let e = error("log(0)*x");
        assert!(e.contains("not positive"), "{e}");
        let e = error("(-2)^(1/2)*x");
        assert!(e.contains("no real value"), "{e}");
        let e = error("0^-1*x");
        assert!(e.contains("divides by zero"), "{e}");
        let e = error("sqrt()*x");
        assert!(e.contains("needs a value"), "{e}");
        let e = error("exp(1000)*x");
        assert!(e.contains("not a finite number"), "{e}");
    }

    #[test]
    fn direct_evaluation_agrees_with_the_folded_expansion() {
        let eq = "sqrt(2)*x^2 + 2^(1/2)*y - (1/4)^-1*z + cos(pi/3)";
        let expr = super::parse(eq).expect("parses");
        let poly = expand(eq).expect("expands");
        let p = [0.3, -1.7, 2.2];
        let direct = expr.eval(p);
        let expanded: f64 = poly
            .terms
            .iter()
            .map(|(e, c)| {
                c.to_f64()
                    * p[0].powi(e[0].into())
                    * p[1].powi(e[1].into())
                    * p[2].powi(e[2].into())
            })
            .sum();
        assert!((direct - expanded).abs() < 1e-12, "{direct} vs {expanded}");
    }
}
