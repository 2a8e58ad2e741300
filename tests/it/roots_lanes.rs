//! The lanes' first-root query (`Solver::first_root_lanes`, both compiled copies) against the
//! scalar query on the heart's and the typed surfaces' corpora, four queries at a time: the
//! same answer bit for bit in every lane.

use kardia::geometry::LANES;
use kardia::roots::Solver;
use kardia::shapes::heart::heart_corpus;
use kardia::shapes::implicit::typed_corpus;

/// Both copies of the lanes' query on `queries` in groups of [`LANES`] (the last group, and
/// every fifth one, with idle lanes), against the scalar query; the hits counted.
fn check<const D: usize>(queries: &[([f64; D], f64, f64)]) -> usize {
    let mut hits = 0;
    for (g, group) in queries.chunks(LANES).enumerate() {
        let mut coeffs = [[0.0; D]; LANES];
        let (mut lo, mut hi) = ([0.0; LANES], [1.0; LANES]);
        let mut active = [false; LANES];
        for (l, (c, a, b)) in group.iter().enumerate() {
            (coeffs[l], lo[l], hi[l]) = (*c, *a, *b);
            active[l] = g % 5 != 4 || l != 1;
        }
        for &(solver, name) in Solver::ALL {
            let detected = solver.first_root_lanes(&coeffs, lo, hi, active);
            let baseline = solver.first_root_lanes_baseline(&coeffs, lo, hi, active);
            for l in 0..LANES {
                let want = if active[l] {
                    solver.first_root(&coeffs[l], lo[l], hi[l])
                } else {
                    None
                };
                let bits = |x: Option<f64>| x.map(f64::to_bits);
                let what = (name, coeffs[l], lo[l], hi[l]);
                assert_eq!(bits(detected[l]), bits(want), "{what:?}");
                assert_eq!(bits(baseline[l]), bits(want), "{what:?}");
                hits += usize::from(want.is_some());
            }
        }
    }
    hits
}

#[test]
fn the_lanes_give_the_scalar_answers_on_the_heart_corpus() {
    let corpus: Vec<_> = heart_corpus()
        .iter()
        .map(|r| (r.coeffs, r.lo, r.hi))
        .collect();
    let hits = check(&corpus);
    assert!(hits > corpus.len() / 2, "{hits} of {}", corpus.len());
}

#[test]
fn the_lanes_give_the_scalar_answers_on_the_typed_corpus() {
    let typed = typed_corpus();
    fn of_length<const D: usize>(typed: &[kardia::shapes::implicit::TypedRay]) -> usize {
        let queries: Vec<([f64; D], f64, f64)> = typed
            .iter()
            .filter_map(|r| Some((r.coeffs.as_slice().try_into().ok()?, r.lo, r.hi)))
            .collect();
        assert!(!queries.is_empty(), "no queries of length {D}");
        check(&queries)
    }
    let hits = of_length::<5>(&typed)
        + of_length::<7>(&typed)
        + of_length::<9>(&typed)
        + of_length::<17>(&typed);
    assert!(hits > typed.len() / 4, "{hits} of {}", typed.len());
}
