//! `REPEAT name FROM first TO last [STEP step]` … `END`: the lines between read once for each
//! value of the loop variable, which expressions of those lines can use (docs/scene-format.md).
//! Loops nest; an error inside one names the iteration at fault (`in iteration i = 17`).
//!
//! The reader of the scene's lines lives here too ([`read_lines`]), since a loop reads its
//! lines again: each line is lexed once, the matching `END` of each `REPEAT` found once, and
//! the statements themselves are read by the parser's `Builder`.

use std::ops::Range;

use super::cursor::{Cursor, Source};
use super::expr::{self, Names, Tapes};
use super::lexer::{lex_line, LexError, Token, TokenKind};
use super::parser::Builder;
use super::words::shorten;
use super::SceneError;

type Result<T> = std::result::Result<T, SceneError>;

/// Most iterations one `REPEAT` may run.
pub const MAX_ITERATIONS: u64 = 1_000_000;
/// Most statements the loops of a scene may read in all (every line of a loop's body counts
/// once per iteration), so that nested loops cannot read without end: loops make at most
/// this many objects.
pub const MAX_LOOP_STATEMENTS: u64 = 1_000_000;

/// A `REPEAT` statement's header, read by [`header`].
#[derive(Debug, Clone)]
pub(super) struct Header {
    /// The loop variable.
    name: String,
    /// Its first value.
    first: f64,
    /// The difference between successive values (not zero).
    step: f64,
    /// How many iterations: the values `first + k·step` from `first` up to `last` (down to,
    /// for a negative step), both included; 0 when `last` is on the other side.
    count: u64,
    /// Whether the values depend on the time.
    uses_time: bool,
}

impl Header {
    /// The loop variable's value at iteration `k` (from 0).
    fn value(&self, k: u64) -> f64 {
        self.first + k as f64 * self.step
    }
}

/// Reads `name FROM first TO last [STEP step]` after the keyword `REPEAT`.
pub(super) fn header(cur: &mut Cursor) -> Result<Header> {
    let Some(t) = cur.peek().filter(|t| t.kind == TokenKind::Word) else {
        return Err(cur.unexpected("the loop variable's name"));
    };
    let name = cur.text(&t);
    let valid = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid {
        return Err(cur.fail(
            t.span,
            format!(
                "`{}` is not a valid name: names start with a letter or `_` and contain only \
                 letters, digits and `_`",
                shorten(name, 30)
            ),
            "invalid name",
        ));
    }
    if expr::is_reserved(name) {
        return Err(cur.fail(
            t.span,
            format!("`{name}` is a built-in name and cannot be a loop variable"),
            "reserved name",
        ));
    }
    if let Some(line) = cur.names.defined_on(name) {
        return Err(cur.fail(
            t.span,
            format!("`{name}` is already defined on line {line}"),
            "defined twice",
        ));
    }
    cur.pos += 1;
    keyword(cur, "FROM")?;
    let (first, _) = cur.number("the loop variable's first value")?;
    keyword(cur, "TO")?;
    let (last, last_span) = cur.number("the loop variable's last value")?;
    let (step, step_span) = if cur
        .peek_word()
        .is_some_and(|w| w.eq_ignore_ascii_case("STEP"))
    {
        cur.pos += 1;
        cur.number("the step between values")?
    } else {
        (1.0, cur.here())
    };
    cur.end()?;
    if step == 0.0 {
        return Err(cur.fail(step_span, "the STEP of a REPEAT must not be 0", "zero step"));
    }
    // The number of values `first + k·step` on the way to `last`, both ends included (a
    // small tolerance keeps `0 TO 1 STEP 0.1` at 11 values).
    let span = (last - first) / step;
    let count = if span < -1e-9 {
        0.0
    } else {
        (span + 1e-9).floor() + 1.0
    };
    if count.is_nan() || count > MAX_ITERATIONS as f64 {
        return Err(cur.fail(
            Cursor::join(&t.span, &last_span),
            format!(
                "this REPEAT would run {} iterations; at most {MAX_ITERATIONS} are allowed",
                super::cursor::show_value(count)
            ),
            "too many iterations",
        ));
    }
    Ok(Header {
        name: name.to_string(),
        first,
        step,
        count: count as u64,
        uses_time: cur.uses_time,
    })
}

/// Steps over the keyword `word` (any case), or fails saying it was expected.
fn keyword(cur: &mut Cursor, word: &str) -> Result<()> {
    if cur
        .peek_word()
        .is_some_and(|w| w.eq_ignore_ascii_case(word))
    {
        cur.pos += 1;
        Ok(())
    } else {
        Err(cur.unexpected(&format!("`{word}`")))
    }
}

/// One line of the scene text, lexed.
struct Line {
    /// 1-based line number.
    number: usize,
    /// Where the next line starts (byte offset).
    next_line: usize,
    /// Its tokens, or why it has none.
    tokens: std::result::Result<Vec<Token>, LexError>,
    /// For a `REPEAT` line, the index of its `END` line, if it has one.
    end: Option<usize>,
    /// Whether it is an `END` line.
    is_end: bool,
}

/// Reads every statement of `text` into `builder`, with `names` for the expressions, running
/// the `REPEAT` loops; returns where the last token of the text ends (for an error about
/// something missing at the end).
pub(super) fn read_lines(src: Source, builder: &mut Builder, names: &mut Names) -> Result<usize> {
    let text = src.text;
    let mut lines = Vec::new();
    let mut offset = 0;
    let mut last_token_end = 0;
    for (i, raw) in text.split('\n').enumerate() {
        let start = offset;
        offset += raw.len() + 1;
        let tokens = lex_line(text, start, start + raw.len());
        let first_word = match &tokens {
            Ok(t) => {
                if let Some(last) = t.last() {
                    last_token_end = last.span.end;
                }
                t.first()
                    .filter(|t| t.kind == TokenKind::Word)
                    .map(|t| &text[t.span.clone()])
            }
            Err(_) => None,
        };
        let is_end = first_word.is_some_and(|w| w.eq_ignore_ascii_case("END"));
        let is_repeat = first_word.is_some_and(|w| w.eq_ignore_ascii_case("REPEAT"));
        if matches!(&tokens, Ok(t) if t.is_empty()) {
            continue;
        }
        lines.push((
            is_repeat,
            Line {
                number: i + 1,
                next_line: offset.min(text.len()),
                tokens,
                end: None,
                is_end,
            },
        ));
    }
    // Each END closes the latest REPEAT still open.
    let mut open = Vec::new();
    for k in 0..lines.len() {
        if lines[k].0 {
            open.push(k);
        } else if lines[k].1.is_end {
            if let Some(r) = open.pop() {
                lines[r].1.end = Some(k);
            }
        }
    }
    let lines: Vec<Line> = lines.into_iter().map(|(_, line)| line).collect();
    let mut reader = Reader {
        src,
        lines: &lines,
        iterations: Vec::new(),
        statements: 0,
        tapes: Tapes::default(),
    };
    reader.run(0..lines.len(), builder, names)?;
    Ok(last_token_end)
}

/// What the loops are doing while the lines are read.
struct Reader<'a> {
    src: Source<'a>,
    lines: &'a [Line],
    /// The loops being run, outermost first: each variable and its value.
    iterations: Vec<(String, f64)>,
    /// Statements read inside loops so far.
    statements: u64,
    /// The expressions read inside loops, kept to compute again at the next iterations.
    tapes: Tapes,
}

impl Reader<'_> {
    /// Reads the lines `range` (inside a loop: one iteration of its body) in order; the
    /// names a loop body defines with `LET` are forgotten after each of its iterations.
    fn run(&mut self, range: Range<usize>, builder: &mut Builder, names: &mut Names) -> Result<()> {
        let mut defined = Vec::new();
        let lines = self.lines;
        let mut k = range.start;
        while k < range.end {
            let line = &lines[k];
            let src = self.src;
            let tokens = match &line.tokens {
                Ok(tokens) => tokens.clone(),
                Err(e) => {
                    let error = src.error(e.span.clone(), e.message.clone(), e.label.clone(), None);
                    return Err(self.in_iteration(error));
                }
            };
            if !self.iterations.is_empty() {
                self.statements += 1;
                if self.statements > MAX_LOOP_STATEMENTS {
                    let span = tokens[0].span.start..tokens.last().map_or(0, |t| t.span.end);
                    let error = src.error(
                        span,
                        format!(
                            "the scene's REPEAT loops read more than {MAX_LOOP_STATEMENTS} \
                             statements in all"
                        ),
                        "one statement too many",
                        Some("make the loops shorter".into()),
                    );
                    return Err(self.in_iteration(error));
                }
            }
            let mut cur = Cursor {
                src,
                tokens,
                pos: 0,
                line: line.number,
                next_line: line.next_line,
                keyword: "",
                usage: "",
                part_usage: None,
                names,
                uses_time: false,
                tapes: (!self.iterations.is_empty()).then_some(&mut self.tapes),
            };
            let read = builder.statement(&mut cur);
            let keyword_span = cur.tokens[0].span.clone();
            builder.uses_time |= cur.uses_time;
            read.map_err(|e| self.in_iteration(e))?;
            if let Some((name, value, uses_time)) = builder.defined.take() {
                expr::define(names, name.clone(), value, uses_time, line.number);
                defined.push(name);
            }
            if line.is_end {
                return Err(self.in_iteration(src.error(
                    keyword_span,
                    "END without a REPEAT before it",
                    "nothing to end",
                    Some("each END closes the nearest REPEAT above it that is still open".into()),
                )));
            }
            if let Some(header) = builder.repeat.take() {
                let Some(end) = line.end else {
                    return Err(self.in_iteration(src.error(
                        keyword_span,
                        "this REPEAT has no END",
                        "never ended",
                        Some("add a line `END` after the statements to repeat".into()),
                    )));
                };
                for i in 0..header.count {
                    let value = header.value(i);
                    expr::define(
                        names,
                        header.name.clone(),
                        value,
                        header.uses_time,
                        line.number,
                    );
                    self.iterations.push((header.name.clone(), value));
                    let result = self.run(k + 1..end, builder, names);
                    self.iterations.pop();
                    names.forget(&header.name);
                    result?;
                }
                k = end + 1;
                continue;
            }
            k += 1;
        }
        if !self.iterations.is_empty() {
            for name in &defined {
                names.forget(name);
            }
        }
        Ok(())
    }

    /// `error` with the iterations being run appended to its message
    /// (` (in iteration i = 17, j = 3)`), as it is when no loop runs.
    fn in_iteration(&self, mut error: SceneError) -> SceneError {
        if self.iterations.is_empty() {
            return error;
        }
        if let SceneError::Invalid(e) = &mut error {
            let values: Vec<String> = self
                .iterations
                .iter()
                .map(|(name, value)| format!("{name} = {value}"))
                .collect();
            e.message = format!("{} (in iteration {})", e.message, values.join(", "));
        }
        error
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::{parse, LoadOptions};

    const HEAD: &str = "CAMERA (10, 0, 0) (0, 0, 0) (0, 0, 1) 40\n";

    fn load(body: &str) -> Result<crate::scene::Scene, String> {
        parse(&format!("{HEAD}{body}"), "t.scene", &LoadOptions::default())
            .map_err(|e| e.to_string())
    }

    fn centres(body: &str) -> Vec<(f64, f64, f64)> {
        load(body)
            .unwrap()
            .objects
            .iter()
            .map(|o| {
                let c = (o.bounds.min + o.bounds.max) * 0.5;
                (c.x, c.y, c.z)
            })
            .collect()
    }

    #[test]
    fn a_loop_makes_one_object_an_iteration_with_its_value() {
        let c = centres("REPEAT i FROM 1 TO 3\n  SPHERE (0, i, 2*i) 0.5 (1, 0, 0)\nEND\n");
        assert_eq!(c, vec![(0.0, 1.0, 2.0), (0.0, 2.0, 4.0), (0.0, 3.0, 6.0)]);
    }

    #[test]
    fn loops_nest_and_steps_count_down() {
        let c = centres(
            "REPEAT i FROM 0 TO 1\nREPEAT j FROM 2 TO 0 STEP -2\nSPHERE (i, j, 0) 0.1 (1, 1, 1)\nEND\nEND\n",
        );
        assert_eq!(
            c,
            vec![
                (0.0, 2.0, 0.0),
                (0.0, 0.0, 0.0),
                (1.0, 2.0, 0.0),
                (1.0, 0.0, 0.0)
            ]
        );
        // A fractional step reaches its last value; a last value before the first: no iteration.
        assert_eq!(
            centres("REPEAT t FROM 0 TO 1 STEP 0.1\nSPHERE (t, 0, 0) 0.1 (1, 1, 1)\nEND").len(),
            11
        );
        assert!(centres("REPEAT t FROM 1 TO 0\nSPHERE (t, 0, 0) 0.1 (1, 1, 1)\nEND").is_empty());
    }

    #[test]
    fn a_let_in_a_body_is_new_at_each_iteration_and_names_end_with_their_loop() {
        let c = centres(
            "REPEAT i FROM 1 TO 2\nLET r = i / 10\nSPHERE (0, 0, r) r (1, 1, 1)\nEND\n\
             REPEAT i FROM 5 TO 5\nSPHERE (i, 0, 0) 1 (1, 1, 1)\nEND\n",
        );
        assert_eq!(c, vec![(0.0, 0.0, 0.1), (0.0, 0.0, 0.2), (5.0, 0.0, 0.0)]);
        let e = load("REPEAT i FROM 1 TO 2\nEND\nSPHERE (i, 0, 0) 1 (1, 1, 1)\n").unwrap_err();
        assert!(e.contains("t.scene:4:"), "{e}");
    }

    #[test]
    fn expressions_kept_from_an_earlier_iteration_use_the_names_values_of_this_one() {
        // A LET of the body, redefined at each iteration, used by the next line; an inner
        // loop whose bounds depend on the outer variable; the inner variable's name then
        // defined by a LET of the outer body.
        let c = centres(
            "REPEAT i FROM 1 TO 2\n\
               LET r = i * i\n\
               SPHERE (r, 2 * r, 0) 0.1 (1, 1, 1)\n\
               REPEAT k FROM i TO 2\n\
                 SPHERE (i, k, 10*i + k) 0.1 (1, 1, 1)\n\
               END\n\
               LET k = 100 * i\n\
               SPHERE (0, 0, k + r) 0.1 (1, 1, 1)\n\
             END\n",
        );
        assert_eq!(
            c,
            vec![
                (1.0, 2.0, 0.0),
                (1.0, 1.0, 11.0),
                (1.0, 2.0, 12.0),
                (0.0, 0.0, 101.0),
                (4.0, 8.0, 0.0),
                (2.0, 2.0, 22.0),
                (0.0, 0.0, 204.0)
            ]
        );
        // An expression that computed at the first iterations fails at a later one with the
        // reader's own error, and a name that a kept expression uses must still be defined.
        let e = load("REPEAT i FROM 0 TO 3\nSPHERE (0, 0, 0) 0.5 + sqrt(2 - i) (1, 1, 1)\nEND\n")
            .unwrap_err();
        assert!(e.contains("t.scene:3:"), "{e}");
        assert!(
            e.contains("sqrt of a negative number (-1) (in iteration i = 3)"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_the_iteration_at_fault() {
        let e = load("REPEAT i FROM 0 TO 30\nSPHERE (0, 0, 0) 1/(17 - i) (1, 1, 1)\nEND\n")
            .unwrap_err();
        assert!(e.contains("t.scene:3:"), "{e}");
        assert!(e.ends_with("(in iteration i = 17)"), "{e}");
        let e = load(
            "REPEAT i FROM 0 TO 3\nREPEAT j FROM 0 TO 3\nSPHERE (0, 0, 0) 1 - i*j/4 (1, 1, 1)\nEND\nEND\n",
        )
        .unwrap_err();
        assert!(e.ends_with("(in iteration i = 2, j = 2)"), "{e}");
    }

    #[test]
    fn malformed_loops_are_errors_at_their_line() {
        for (body, line, words) in [
            (
                "REPEAT i FROM 0 TO 2\nSPHERE (0,0,0) 1 (1,1,1)\n",
                2,
                "has no END",
            ),
            ("END\n", 2, "END without a REPEAT"),
            ("REPEAT i FROM 0 TO 2 STEP 0\nEND\n", 2, "must not be 0"),
            ("REPEAT pi FROM 0 TO 2\nEND\n", 2, "built-in name"),
            (
                "LET k = 1\nREPEAT k FROM 0 TO 2\nEND\n",
                3,
                "already defined on line 2",
            ),
            (
                "REPEAT i FROM 0 TO 2\nREPEAT i FROM 0 TO 2\nEND\nEND\n",
                3,
                "already defined",
            ),
            ("REPEAT i FROM 0 TO 1e7\nEND\n", 2, "at most 1000000"),
            ("REPEAT i 0 TO 2\nEND\n", 2, "expected `FROM`"),
            ("REPEAT i FROM 0 TO 2 3\nEND\n", 2, "expected end of line"),
            (
                "REPEAT i FROM 1 TO 1000\nREPEAT j FROM 1 TO 1000\nLET a = j\nEND\nEND\n",
                4,
                "more than 1000000 statements",
            ),
            (
                "REPEAT i FROM 0 TO 1\nMATERIAL m (1, 1, 1)\nEND\n",
                3,
                "already defined",
            ),
        ] {
            let e = load(body).unwrap_err();
            assert!(e.contains(&format!("t.scene:{line}:")), "{body}: {e}");
            assert!(e.contains(words), "{body}: {e}");
        }
    }
}
