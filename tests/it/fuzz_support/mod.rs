//! The scene fuzzer shared by the CI sample (`tests/it/fuzz_scenes.rs`) and the long
//! campaign (`examples/fuzz.rs`, driven by `bench/fuzz.sh`): mutates the scenes in scenes/
//! and a scene that uses every keyword, surface property and preset, parses each result
//! and, when it parses, renders it tiny (12×9, 1 sample per pixel), checking that nothing
//! panics, every pixel is finite and every case is quick.
#![allow(dead_code)]

use kardia::integrator::{trace_ray, ShadeSetup, View};
use kardia::pipeline::{Control, RenderRequest, Renderer};
use kardia::scene::{limits, parse, LoadOptions, Scene, SceneError};
use rand::{Rng, SeedableRng};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};

/// Width and height of the render of a case that parses.
pub const RENDER_SIZE: (u32, u32) = (12, 9);

/// A scene with every statement and surface property, both light forms, a quoted quadric
/// and the `heart` preset (a HEART); the other presets come from scenes/implicit/, whose
/// surfaces take milliseconds each to load.
pub const EVERY_KEYWORD: &str = r#"SIZE 64 48
FRAMES 4 FPS 12
LET s = 0.5 + 0.25*sin(2*pi*clock)
CAMERA (8, 2, 3) (0, 0, 0.2) (0, 0, 1) 45
BACKGROUND (0.05, 0.05, 0.1)
AMBIENT (0.05, 0.05, 0.05)
LIGHT (6, -4, 6) (0.9, 0.9, 0.9)
LIGHT (3, 6, 4) (0.4, 0.4, 0.5) 0.5 SAMPLES 4
MATERIAL glass (0.02, 0.02, 0.02) SPECULAR 0.9 200 REFLECT 0.08 TRANSMIT 0.9 IOR 1.5
MATERIAL tinted glass ATTENUATION (0.05, 0.4, 0.35) INSIDE (0.9, 0.8, 0.2)
HEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.75, 0.04, 0.08) SPECULAR 0.6 80
SPHERE (-1, -2.6, -0.2) 0.8 (0.1, 0.1, 0.1) REFLECT 0.8
SPHERE (1, 2, 0) s tinted
PLANE (0, 0, -1) (0, 0, 1) (0.9, 0.9, 0.9) CHECKER (0.1, 0.1, 0.12) 0.5
BOX (1.2, 1.8, -1) (0.866, 0.5, 0) (-0.5, 0.866, 0) (0, 0, 1) (0.15, 0.3, 0.8) SPECULAR 0.3 30
POLYGON 4 (-2.49, -3, -1) (-2.49, 3, -1) (-2.49, 3, 2.5) (-2.49, -3, 2.5) (0.05, 0.05, 0.05) REFLECT 0.9
ELLIPSOID (-1.8, 2.4, -0.3) (0.5, 0, 0) (0, 0.9, 0) (0, 0, 0.7) (0.2, 0.7, 0.3)
IMPLICIT "x^2 + y^2 = s^2" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.3, 0.3, 0.8) INSIDE (0.9, 0.8, 0.2) BOUND 2
IMPLICIT heart (0, 3, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.8, 0.1, 0.1) INSIDE (1, 0.9, 0.6) BOUND 0.9
"#;

/// Words the fuzzer puts where a keyword, property, preset or name was.
pub const WORDS: &[&str] = &[
    "SIZE",
    "CAMERA",
    "BACKGROUND",
    "AMBIENT",
    "LIGHT",
    "MATERIAL",
    "SPHERE",
    "PLANE",
    "BOX",
    "POLYGON",
    "ELLIPSOID",
    "HEART",
    "IMPLICIT",
    "SPECULAR",
    "REFLECT",
    "TRANSMIT",
    "IOR",
    "ATTENUATION",
    "CHECKER",
    "INSIDE",
    "BOUND",
    "SAMPLES",
    "heart",
    "taubin_heart",
    "torus",
    "kummer",
    "barth_sextic",
    "clebsch",
    "chmutov",
    "glass",
    "tinted",
    "chrome",
    "sphere",
    "LET",
    "FRAMES",
    "FPS",
    "clock",
    "frame",
    "frames",
    "pi",
    "s",
    "sin",
    "cos",
    "tan",
    "sqrt",
    "abs",
    "min",
    "max",
    "^",
    "/",
    "*",
    "(",
    ")",
    "=",
    "é",
    "\u{feff}",
];

/// Expressions the fuzzer puts where a number was: undefined or overflowing arithmetic,
/// the time variables, unbalanced and malformed forms.
pub const EXPRESSIONS: &[&str] = &[
    "1/0",
    "-1/0",
    "0/0",
    "sqrt(-1)",
    "2^1024",
    "2^-1075",
    "(-8)^(1/3)",
    "0^0",
    "0^-1",
    "1e308*10",
    "-(1e308+1e308)",
    "clock/0",
    "1/clock",
    "frame/frames",
    "frames*32768",
    "sin(1e308)",
    "tan(pi/2)",
    "min(1)",
    "max(1, 2, 3)",
    "max(,)",
    "abs(-0)",
    "-(-(-1))",
    "pi^pi^pi^pi",
    "(((((((1)))))))",
    "((1",
    "1))",
    "s*s*s*s*s*s*s*s",
    "undefined_name",
    "sqrt",
    "2 ^",
    "* 3",
];

/// Extreme numbers, in many spellings.
pub const EXTREMES: &[&str] = &[
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "-5e-324",
    "2.2250738585072014e-308",
    "11e-308",
    "1e-308",
    "1e-300",
    "1e300",
    "-0",
    "-0.0",
    "0",
    "+0",
    "32768",
    "32769",
    "65536",
    "65537",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "18446744073709551616",
    "1e19",
    "-1",
    "1",
    "2",
    "3",
    "0.5",
    "16",
    "17",
    "1024",
    "1025",
    "180",
    "179.99999999999997",
    "1e999",
    "-1e999",
    "1e+999999999",
    "1e-999999999",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "-Infinity",
    "INF",
    "0x10",
    "1_000",
    ".",
    "-",
    "1e",
    "e5",
    "1.5.5",
];

/// Clauses the fuzzer appends to a line (`#` is replaced by a random number).
const CLAUSES: &[&str] = &[
    " SPECULAR # #",
    " REFLECT #",
    " TRANSMIT # IOR #",
    " IOR #",
    " ATTENUATION (#, #, #)",
    " CHECKER (#, #, #) #",
    " INSIDE (#, #, #)",
    " BOUND #",
    " # SAMPLES #",
    " SAMPLES #",
    " #",
    " (#, #, #)",
    " glass",
];

/// Near-boundary values of every documented range: each end, one step inside and outside,
/// and a little further out.
pub fn boundary_values() -> Vec<String> {
    let mut out = Vec::new();
    for (_, l) in limits::TABLE {
        for end in [l.min, l.max] {
            if !end.is_finite() {
                continue;
            }
            for x in [
                end,
                end.next_up(),
                end.next_down(),
                end * 1.000001,
                end * 0.999999,
                end + 1.0,
                end - 1.0,
                end * 10.0,
                end / 10.0,
            ] {
                out.push(format!("{x:?}"));
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

/// A value inside a random documented range: one of its ends, or spread over its orders
/// of magnitude.
fn in_range(rng: &mut impl Rng) -> String {
    let (_, l) = limits::TABLE[rng.random_range(0..limits::TABLE.len())];
    let hi = l.max.min(1e6);
    let x = match rng.random_range(0..4) {
        0 => l.min,
        1 => hi,
        _ => {
            let lo = l.min.max(-1e6);
            let magnitude = 10f64.powf(rng.random_range(-6.0..6.0f64));
            (if rng.random_bool(0.5) {
                lo + magnitude
            } else {
                hi - magnitude
            })
            .clamp(lo, hi)
        }
    };
    let x = if l.whole { x.round() } else { x };
    format!("{x:?}")
}

/// One piece of scene text: a word, a punctuation character, or a run of whitespace.
fn pieces(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut word = String::new();
    let mut in_string = false;
    for c in text.chars() {
        if in_string {
            word.push(c);
            if c == '"' || c == '\n' {
                out.push(std::mem::take(&mut word));
                in_string = false;
            }
            continue;
        }
        let punct = matches!(c, '(' | ')' | ',' | '#') || c.is_whitespace();
        if c == '"' {
            if !word.is_empty() {
                out.push(std::mem::take(&mut word));
            }
            word.push(c);
            in_string = true;
        } else if punct {
            if !word.is_empty() {
                out.push(std::mem::take(&mut word));
            }
            out.push(c.to_string());
        } else {
            word.push(c);
        }
    }
    if !word.is_empty() {
        out.push(word);
    }
    out
}

fn is_number(s: &str) -> bool {
    s.parse::<f64>().is_ok()
}

fn is_word(s: &str) -> bool {
    !s.is_empty() && !s.starts_with(|c: char| c.is_whitespace() || "(),#\"".contains(c))
}

/// The mutator: base scenes and the number pools.
pub struct Fuzzer {
    /// Scenes that load in well under a millisecond: scenes/*.scene and [`EVERY_KEYWORD`].
    seeds: Vec<String>,
    /// Scenes whose implicit surfaces take milliseconds to load (scenes/implicit/): chosen
    /// for one case in [`COSTLY_SHARE`], so that a long campaign stays affordable.
    costly: Vec<String>,
    numbers: Vec<String>,
}

/// One case in this many starts from a scene of scenes/implicit/.
pub const COSTLY_SHARE: u32 = 100;

/// What one case did.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// The scene was refused with a well-formed error.
    Refused,
    /// The scene parsed and rendered with finite pixels.
    Rendered,
    /// The scene parsed but its render overflowed: a channel saturated at ±f32::MAX (where
    /// the film stores what would have been infinite).
    NonFinite,
    /// Parsing or rendering panicked (the message).
    Panicked(String),
    /// The error was malformed (the reason).
    BadError(String),
}

/// One case's outcome and how long it took.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What happened.
    pub verdict: Verdict,
    /// Parse plus render time.
    pub elapsed: Duration,
}

/// Counts over a run of cases.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    /// Cases run.
    pub cases: u64,
    /// Cases that parsed.
    pub parsed: u64,
    /// Cases rendered with finite pixels.
    pub rendered: u64,
    /// Cases that panicked.
    pub panics: u64,
    /// Cases with a non-finite pixel.
    pub non_finite: u64,
    /// Cases with a malformed error.
    pub bad_errors: u64,
    /// Cases slower than the time bound.
    pub slow: u64,
    /// The slowest case: its time, index and text.
    pub slowest: (Duration, u64, String),
    /// The first few failing cases: index, verdict, text.
    pub failures: Vec<(u64, Verdict, String)>,
    /// The first few slow cases (that did not fail otherwise): index and text.
    pub slow_cases: Vec<(u64, String)>,
}

impl Tally {
    /// Adds case `index` (text `text`) with its outcome; `bound` is the time bound per case.
    pub fn add(&mut self, index: u64, text: &str, outcome: &Outcome, bound: Duration) {
        self.cases += 1;
        match &outcome.verdict {
            Verdict::Refused => {}
            Verdict::Rendered => {
                self.parsed += 1;
                self.rendered += 1;
            }
            Verdict::NonFinite => {
                self.parsed += 1;
                self.non_finite += 1;
            }
            Verdict::Panicked(_) => self.panics += 1,
            Verdict::BadError(_) => self.bad_errors += 1,
        }
        let failed = !matches!(outcome.verdict, Verdict::Refused | Verdict::Rendered);
        if failed && self.failures.len() < 20 {
            self.failures
                .push((index, outcome.verdict.clone(), text.to_string()));
        }
        if outcome.elapsed > bound {
            self.slow += 1;
            if !failed && self.slow_cases.len() < 1000 {
                self.slow_cases.push((index, text.to_string()));
            }
        }
        if outcome.elapsed > self.slowest.0 {
            self.slowest = (outcome.elapsed, index, text.to_string());
        }
    }

    /// Adds another tally's counts.
    pub fn merge(&mut self, other: Tally) {
        self.cases += other.cases;
        self.parsed += other.parsed;
        self.rendered += other.rendered;
        self.panics += other.panics;
        self.non_finite += other.non_finite;
        self.bad_errors += other.bad_errors;
        self.slow += other.slow;
        if other.slowest.0 > self.slowest.0 {
            self.slowest = other.slowest;
        }
        for f in other.failures {
            if self.failures.len() < 20 {
                self.failures.push(f);
            }
        }
        for c in other.slow_cases {
            if self.slow_cases.len() < 1000 {
                self.slow_cases.push(c);
            }
        }
    }

    /// Whether every case was answered well and in time.
    pub fn clean(&self) -> bool {
        self.panics == 0 && self.non_finite == 0 && self.bad_errors == 0 && self.slow == 0
    }
}

impl Fuzzer {
    /// A fuzzer over the scenes in scenes/ (and scenes/implicit/) and [`EVERY_KEYWORD`].
    pub fn new() -> Self {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let read_dir = |dir: std::path::PathBuf| {
            let mut paths: Vec<_> = std::fs::read_dir(dir)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "scene"))
                .collect();
            paths.sort();
            paths
                .iter()
                .map(|p| std::fs::read_to_string(p).unwrap())
                .collect::<Vec<_>>()
        };
        let mut seeds = read_dir(root.clone());
        // The scene with everything counts for as much as all the others together.
        for _ in 0..seeds.len().max(1) {
            seeds.push(EVERY_KEYWORD.to_string());
        }
        let costly = read_dir(root.join("implicit"));
        let mut numbers: Vec<String> = EXTREMES.iter().map(|s| s.to_string()).collect();
        numbers.extend(boundary_values());
        numbers.extend(EXPRESSIONS.iter().map(|s| s.to_string()));
        Self {
            seeds,
            costly,
            numbers,
        }
    }

    /// The text of case `index` of the run with `seed` (the same pair always gives the same
    /// text).
    pub fn case(&self, seed: u64, index: u64) -> String {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(
            seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ index.wrapping_mul(0xbf58_476d_1ce4_e5b9),
        );
        let base = if rng.random_range(0..COSTLY_SHARE) == 0 {
            &self.costly[rng.random_range(0..self.costly.len())]
        } else {
            &self.seeds[rng.random_range(0..self.seeds.len())]
        };
        let mut p = pieces(base);
        let edits = 1 + rng.random_range(0..3) + rng.random_range(0..2);
        for _ in 0..edits {
            self.edit(&mut rng, &mut p);
        }
        p.concat()
    }

    fn number(&self, rng: &mut impl Rng) -> String {
        match rng.random_range(0..6) {
            0 => format!("{:?}", rng.random_range(-3.0..3.0f64)),
            1 => format!("{}", rng.random_range(0..40)),
            2 | 3 => in_range(rng),
            _ => self.numbers[rng.random_range(0..self.numbers.len())].clone(),
        }
    }

    /// `equation` (a quoted string) with one of its numbers replaced, or an exponent added.
    fn mutate_equation(&self, rng: &mut impl Rng, equation: &str) -> String {
        let chars: Vec<char> = equation.chars().collect();
        let starts: Vec<usize> = (0..chars.len())
            .filter(|&k| {
                chars[k].is_ascii_digit()
                    && (k == 0 || !chars[k - 1].is_ascii_digit() && chars[k - 1] != '.')
            })
            .collect();
        let number = self.number(rng);
        if starts.is_empty() || rng.random_range(0..4) == 0 {
            // An exponent or a factor on a random position.
            let at = rng.random_range(1..chars.len().max(2)).min(chars.len());
            let insert = ["^", "*", "/", "+"][rng.random_range(0..4)];
            let mut out: String = chars[..at].iter().collect();
            out.push_str(&format!("{insert}{number}"));
            out.extend(&chars[at..]);
            return out;
        }
        let start = starts[rng.random_range(0..starts.len())];
        let mut end = start;
        while end < chars.len() && (chars[end].is_ascii_digit() || chars[end] == '.') {
            end += 1;
        }
        let mut out: String = chars[..start].iter().collect();
        out.push_str(&number);
        out.extend(&chars[end..]);
        out
    }

    /// One random edit of the pieces.
    fn edit(&self, rng: &mut impl Rng, p: &mut Vec<String>) {
        if p.is_empty() {
            p.push(WORDS[rng.random_range(0..WORDS.len())].to_string());
            return;
        }
        let at = rng.random_range(0..p.len());
        match rng.random_range(0..16) {
            // Numbers replaced (the most common edit: it keeps the scene parseable).
            0..=4 => {
                let numbers: Vec<usize> = (0..p.len()).filter(|&i| is_number(&p[i])).collect();
                if !numbers.is_empty() {
                    let i = numbers[rng.random_range(0..numbers.len())];
                    p[i] = self.number(rng);
                }
            }
            // A keyword, property, preset or name replaced.
            5 => {
                let words: Vec<usize> = (0..p.len())
                    .filter(|&i| is_word(&p[i]) && !is_number(&p[i]))
                    .collect();
                if !words.is_empty() {
                    let i = words[rng.random_range(0..words.len())];
                    p[i] = WORDS[rng.random_range(0..WORDS.len())].to_string();
                }
            }
            // Deletion of a few pieces.
            6 => {
                let end = (at + 1 + rng.random_range(0..4)).min(p.len());
                p.drain(at..end);
            }
            // Duplication of a few pieces.
            7 => {
                let end = (at + 1 + rng.random_range(0..8)).min(p.len());
                let copy: Vec<String> = p[at..end].to_vec();
                p.splice(end..end, copy);
            }
            // A clause appended to a line.
            8 | 9 => {
                let newline = p[at..]
                    .iter()
                    .position(|s| s == "\n")
                    .map_or(p.len(), |k| at + k);
                let clause = CLAUSES[rng.random_range(0..CLAUSES.len())];
                let mut text = String::new();
                for part in clause.split('#') {
                    if !text.is_empty() || clause.starts_with('#') {
                        text.push_str(&self.number(rng));
                    }
                    text.push_str(part);
                }
                p.insert(newline, text);
            }
            // A splice: a line of another scene inserted, or pieces of it.
            10 | 11 => {
                let other = pieces(&self.seeds[rng.random_range(0..self.seeds.len())]);
                let a = rng.random_range(0..other.len());
                let b = if rng.random_bool(0.5) {
                    other[a..]
                        .iter()
                        .position(|s| s == "\n")
                        .map_or(other.len(), |k| a + k + 1)
                } else {
                    (a + 1 + rng.random_range(0..12)).min(other.len())
                };
                p.splice(at..at, other[a..b].iter().cloned());
            }
            // A piece inserted: a word, a number or punctuation.
            12 => {
                let s = match rng.random_range(0..3) {
                    0 => WORDS[rng.random_range(0..WORDS.len())].to_string(),
                    1 => self.number(rng),
                    _ => ["(", ")", ",", "\"", "#", "\n", "\r\n", " ", "\t"]
                        [rng.random_range(0..9)]
                    .to_string(),
                };
                p.insert(at, s);
            }
            // A keyword's case changed.
            13 => {
                if is_word(&p[at]) {
                    p[at] = if rng.random_bool(0.5) {
                        p[at].to_lowercase()
                    } else {
                        p[at].to_uppercase()
                    };
                }
            }
            // A whole line repeated or swapped with another.
            14 => {
                let start = p[..at].iter().rposition(|s| s == "\n").map_or(0, |k| k + 1);
                let end = p[at..]
                    .iter()
                    .position(|s| s == "\n")
                    .map_or(p.len(), |k| at + k + 1);
                let line: Vec<String> = p[start..end].to_vec();
                let to = rng.random_range(0..=p.len());
                p.splice(to..to, line);
            }
            // A number or an exponent inside a quoted equation replaced.
            15 if rng.random_bool(0.5) => {
                let strings: Vec<usize> = (0..p.len()).filter(|&i| p[i].starts_with('"')).collect();
                if !strings.is_empty() {
                    let i = strings[rng.random_range(0..strings.len())];
                    p[i] = self.mutate_equation(rng, &p[i]);
                }
            }
            // A random character.
            _ => {
                let c = char::from_u32(rng.random_range(0..0x3000)).unwrap_or('?');
                p.insert(at, c.to_string());
            }
        }
    }
}

impl Default for Fuzzer {
    fn default() -> Self {
        Self::new()
    }
}

/// Parses `text` and, when it parses, renders it at [`RENDER_SIZE`] with 1 sample per pixel
/// on one thread and traces its pixels' centre rays in every view ([`renders_finite`]);
/// never panics itself (a panic inside is caught and reported).
pub fn run_case(text: &str, seed: u64) -> Outcome {
    let start = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| check_case(text, seed)));
    let verdict = match result {
        Ok(v) => v,
        Err(payload) => Verdict::Panicked(panic_message(&*payload)),
    };
    Outcome {
        verdict,
        elapsed: start.elapsed(),
    }
}

/// The text of a panic payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else {
        "(a panic without a message)".into()
    }
}

fn check_case(text: &str, seed: u64) -> Verdict {
    let scene = match parse(text, "fuzz.scene", &LoadOptions::default()) {
        Ok(scene) => scene,
        Err(e) => return check_error(text, e),
    };
    if renders_finite(&scene, seed) {
        Verdict::Rendered
    } else {
        Verdict::NonFinite
    }
}

thread_local! {
    /// One renderer (a one-thread pool) per fuzzing thread, reused by every case.
    static RENDERER: Renderer = Renderer::new(1).expect("a one-thread render pool");
}

/// Renders `scene` at [`RENDER_SIZE`] with 1 sample per pixel through the pipeline, and
/// traces each pixel's centre ray in every view: true when every pixel of the image is
/// finite and below the film's clamp (`f32::MAX`, where an overflow would be stored), and
/// every traced colour is finite before it reaches the film (which would turn a NaN into 0).
pub fn renders_finite(scene: &Scene, seed: u64) -> bool {
    let (width, height) = RENDER_SIZE;
    let request = RenderRequest {
        width: Some(width),
        height: Some(height),
        spp: 1,
        seed,
        max_depth: 8,
        ..RenderRequest::default()
    };
    let rendered = RENDERER.with(|r| r.render(scene, &request, &Control::default()));
    let Ok(rendered) = rendered else {
        return false;
    };
    let stored_ok = rendered
        .image
        .pixels
        .iter()
        .all(|p| p.is_finite() && p.abs().max_element() < f32::MAX);
    let setup = ShadeSetup {
        scene,
        camera: &scene.camera,
        spp: 1,
        max_depth: 8,
        max_shadow_rays: None,
    };
    let traced_ok = (0..height).all(|y| {
        (0..width).all(|x| {
            let ray = scene
                .camera
                .ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
            View::ALL
                .iter()
                .all(|&(view, _)| trace_ray(view, &setup, seed, &ray).is_finite())
        })
    });
    stored_ok && traced_ok
}

/// Checks that a parse error is well formed: located, on character boundaries, showable.
fn check_error(text: &str, e: SceneError) -> Verdict {
    let Some((line, column)) = e.location() else {
        return Verdict::BadError("a parse error without a location".into());
    };
    if line < 1 || column < 1 || line > text.split('\n').count() {
        return Verdict::BadError(format!("location {line}:{column} outside the text"));
    }
    if !e
        .to_string()
        .starts_with(&format!("fuzz.scene:{line}:{column}: "))
    {
        return Verdict::BadError(format!("one-line form `{e}`"));
    }
    if let SceneError::Invalid(b) = &e {
        let end = b.span.offset() + b.span.len();
        if end > text.len()
            || !text.is_char_boundary(b.span.offset())
            || !text.is_char_boundary(end)
        {
            return Verdict::BadError("span outside the text or inside a character".into());
        }
    }
    if format!("{:?}", miette::Report::new(e)).is_empty() {
        return Verdict::BadError("empty report".into());
    }
    Verdict::Refused
}

/// Re-times the slow cases of `tally` alone, three times each, and keeps as slow only those
/// whose fastest run is still over `bound` (on a loaded machine, a case can be descheduled
/// for seconds); returns how many were dropped.
pub fn confirm_slow(tally: &mut Tally, seed: u64, bound: Duration) -> u64 {
    if tally.slow as usize > tally.slow_cases.len() {
        return 0; // Too many to re-time: keep the count as measured.
    }
    let before = tally.slow_cases.len();
    tally.slow_cases.retain(|(index, text)| {
        let best = (0..3)
            .map(|_| run_case(text, seed ^ index).elapsed)
            .min()
            .unwrap_or_default();
        best > bound
    });
    let dropped = (before - tally.slow_cases.len()) as u64;
    tally.slow -= dropped;
    dropped
}

/// Runs cases `first..first + count` of the run with `seed`.
pub fn run(fuzzer: &Fuzzer, seed: u64, first: u64, count: u64, bound: Duration) -> Tally {
    let mut tally = Tally::default();
    for index in first..first + count {
        let text = fuzzer.case(seed, index);
        let outcome = run_case(&text, seed ^ index);
        tally.add(index, &text, &outcome, bound);
    }
    tally
}
