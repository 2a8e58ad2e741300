//! The parser never panics: random bytes, token soup and random mutations of the scenes in
//! scenes/ all give a scene or an error (and every error renders with its caret).

use crate::fuzz_support::WORDS;
use kardia::scene::{parse, LoadOptions, SceneError};
use proptest::prelude::*;
use std::sync::OnceLock;

/// Parses `text`; on error checks that the error is well formed and renders.
fn parse_never_panics(text: &str) {
    match parse(text, "fuzz.scene", &LoadOptions::default()) {
        Ok(scene) => {
            assert!(scene.width >= 1 && scene.width <= 32768);
            assert!(scene.height >= 1 && scene.height <= 32768);
        }
        Err(e) => {
            let (line, column) = e.location().expect("parse errors have a location");
            assert!(line >= 1 && column >= 1);
            assert!(line <= text.split('\n').count());
            assert!(e
                .to_string()
                .starts_with(&format!("fuzz.scene:{line}:{column}: ")));
            if let SceneError::Invalid(b) = &e {
                let end = b.span.offset() + b.span.len();
                assert!(end <= text.len());
                assert!(text.is_char_boundary(b.span.offset()) && text.is_char_boundary(end));
            }
            let shown = format!("{:?}", miette::Report::new(e));
            assert!(!shown.is_empty());
        }
    }
}

/// The text of every scene in scenes/.
fn scenes() -> &'static [String] {
    static SCENES: OnceLock<Vec<String>> = OnceLock::new();
    SCENES.get_or_init(|| {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut texts: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "scene"))
            .map(|p| std::fs::read_to_string(p).unwrap())
            .collect();
        texts.sort();
        texts
    })
}

/// Pieces besides the fuzzer's keywords and names (`fuzz_support::WORDS`) that are likely to
/// reach deep into the parser: punctuation, line ends, numbers at and past their limits.
const PIECES: &[&str] = &[
    ",",
    "\"",
    "\"x^2 + y^2 = 1\"",
    "\"\"",
    "#",
    "\n",
    "\r\n",
    " ",
    "\t",
    "0",
    "1",
    "-1",
    "3",
    "0.5",
    "2",
    "180",
    "1e999",
    "-1e999",
    "nan",
    "inf",
    "1e-320",
    "32768",
    "32769",
    "1e308",
    "-1e308",
    "4294967296",
    "(0,0,0)",
    "(1,0,0)",
    "(0,1,0)",
    "(0,0,1)",
    "(1,1,1)",
    "(1e300,1,1)",
];

/// Every piece the soups and edits draw from: the keywords and names, then [`PIECES`].
fn vocabulary() -> &'static [&'static str] {
    static ALL: OnceLock<Vec<&'static str>> = OnceLock::new();
    ALL.get_or_init(|| WORDS.iter().chain(PIECES).copied().collect())
}

fn soup() -> impl Strategy<Value = String> {
    proptest::collection::vec(
        (
            0..vocabulary().len(),
            prop_oneof![Just(" "), Just(""), Just("\n")],
        ),
        0..80,
    )
    .prop_map(|parts| {
        let mut s = String::from("CAMERA (5,0,0) (0,0,0) (0,0,1) 40\n");
        for (i, sep) in parts {
            s.push_str(vocabulary()[i]);
            s.push_str(sep);
        }
        s
    })
}

#[derive(Debug, Clone)]
enum Edit {
    Delete(usize, usize),
    Insert(usize, usize),
    InsertChar(usize, char),
    Duplicate(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 1..12usize).prop_map(|(at, n)| Edit::Delete(at, n)),
        (any::<usize>(), 0..vocabulary().len()).prop_map(|(at, i)| Edit::Insert(at, i)),
        (any::<usize>(), any::<char>()).prop_map(|(at, c)| Edit::InsertChar(at, c)),
        (any::<usize>(), 1..40usize).prop_map(|(at, n)| Edit::Duplicate(at, n)),
    ]
}

fn mutate(text: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for e in edits {
        let len = chars.len();
        let pos = |at: usize| if len == 0 { 0 } else { at % (len + 1) };
        match *e {
            Edit::Delete(at, n) => {
                let a = pos(at).min(len);
                let b = (a + n).min(len);
                chars.drain(a..b);
            }
            Edit::Insert(at, i) => {
                let a = pos(at);
                chars.splice(a..a, vocabulary()[i].chars());
            }
            Edit::InsertChar(at, c) => chars.insert(pos(at), c),
            Edit::Duplicate(at, n) => {
                let a = pos(at).min(len);
                let b = (a + n).min(len);
                let copy: Vec<char> = chars[a..b].to_vec();
                chars.splice(b..b, copy);
            }
        }
    }
    chars.into_iter().collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        parse_never_panics(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn random_printable_text(text in "[ -~\t\n]{0,300}") {
        parse_never_panics(&text);
    }

    #[test]
    fn token_soup(text in soup()) {
        parse_never_panics(&text);
    }

    #[test]
    fn mutated_scenes(which in any::<usize>(), edits in proptest::collection::vec(edit(), 1..6)) {
        let all = scenes();
        let text = mutate(&all[which % all.len()], &edits);
        parse_never_panics(&text);
    }
}
