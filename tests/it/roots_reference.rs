//! The first-root answers of every strategy on both fixed corpora (the heart's and the typed
//! surfaces', the ones `cargo bench --bench roots` times) against the answers recorded in
//! `tests/data/roots_reference.txt`: the same hit or miss on every query, and the same root
//! to [`TOLERANCE`]. A speed change to the root finders (or to how the corpora's polynomials
//! are formed) must keep this test passing unchanged. After an intended change of answers,
//! regenerate the file with `KARDIA_BLESS=1 cargo test --test it roots_reference` and say in
//! the commit which queries changed and why.

use kardia::roots::Solver;
use kardia::shapes::heart::heart_corpus;
use kardia::shapes::implicit::typed_corpus;
use std::fmt::Write;

/// Largest difference allowed between a root and its recorded value, relative to
/// `max(1, |t|)` (the file keeps 16 significant digits).
const TOLERANCE: f64 = 1e-12;

const REFERENCE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/roots_reference.txt"
);

/// Every query of both corpora: a label, the coefficients and the interval.
fn queries() -> Vec<(String, Vec<f64>, f64, f64)> {
    let mut out: Vec<_> = heart_corpus()
        .into_iter()
        .enumerate()
        .map(|(i, r)| (format!("heart {i}"), r.coeffs.to_vec(), r.lo, r.hi))
        .collect();
    out.extend(
        typed_corpus()
            .into_iter()
            .enumerate()
            .map(|(i, r)| (format!("{} {i}", r.surface), r.coeffs, r.lo, r.hi)),
    );
    out
}

fn show(t: Option<f64>) -> String {
    t.map_or("-".into(), |t| format!("{t:.15e}"))
}

fn parse(s: &str) -> Option<f64> {
    (s != "-").then(|| s.parse().expect("a recorded root"))
}

#[test]
fn answers_on_both_corpora_are_the_recorded_ones() {
    let queries = queries();
    let answers: Vec<Vec<Option<f64>>> = queries
        .iter()
        .map(|(_, c, lo, hi)| {
            Solver::ALL
                .iter()
                .map(|(s, _)| s.first_root(c, *lo, *hi))
                .collect()
        })
        .collect();
    if std::env::var_os("KARDIA_BLESS").is_some() {
        let mut text = String::from("# label | one first root per solver (");
        let names: Vec<_> = Solver::ALL.iter().map(|(_, n)| *n).collect();
        writeln!(text, "{}), '-' for none", names.join(", ")).unwrap();
        for ((label, ..), a) in queries.iter().zip(&answers) {
            let cols: Vec<_> = a.iter().map(|t| show(*t)).collect();
            writeln!(text, "{label} | {}", cols.join(" ")).unwrap();
        }
        std::fs::create_dir_all(std::path::Path::new(REFERENCE).parent().unwrap()).unwrap();
        std::fs::write(REFERENCE, text).unwrap();
        return;
    }
    let text = std::fs::read_to_string(REFERENCE)
        .unwrap_or_else(|e| panic!("cannot read {REFERENCE}: {e} (bless with KARDIA_BLESS=1)"));
    let recorded: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(recorded.len(), queries.len(), "the corpora changed size");
    let mut wrong = Vec::new();
    let mut hits = 0;
    for (((label, ..), got), line) in queries.iter().zip(&answers).zip(&recorded) {
        let (rec_label, cols) = line.split_once(" | ").expect("label | answers");
        assert_eq!(rec_label, label, "the corpora changed order");
        let cols: Vec<_> = cols.split(' ').map(parse).collect();
        assert_eq!(cols.len(), got.len());
        for ((&want, &have), (_, solver)) in cols.iter().zip(got).zip(Solver::ALL) {
            hits += usize::from(have.is_some());
            let same = match (want, have) {
                (None, None) => true,
                (Some(a), Some(b)) => (a - b).abs() <= TOLERANCE * a.abs().max(1.0),
                _ => false,
            };
            if !same {
                wrong.push(format!(
                    "{label} ({solver}): recorded {want:?}, now {have:?}"
                ));
            }
        }
    }
    assert!(hits > 1000, "{hits}");
    assert!(
        wrong.is_empty(),
        "{} answers changed:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
