//! `first_root` on two fixed corpora, for every strategy: the heart's
//! (`kardia::shapes::heart::heart_corpus`: camera rays through an axis-aligned heart, each
//! restricted to its bounding box, hits and misses) and the typed surfaces'
//! (`kardia::shapes::implicit::typed_corpus`: the queries the generic implicit path puts to
//! the solver for camera rays through a torus, Barth's sextic, Chmutov's octic and a sphere
//! written with degree 16), one benchmark per degree; and the lanes' query
//! (`Solver::first_root_lanes`) on the same corpora taken in groups of four (the last group
//! with idle lanes; a typed query with fewer coefficients than its degree's padded with zeros).
//! The throughput line gives queries per second: ns per query = 1e9 / that.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use kardia::geometry::LANES;
use kardia::roots::Solver;
use kardia::shapes::heart::heart_corpus;
use kardia::shapes::implicit::{typed_corpus, TYPED_SURFACES};
use std::hint::black_box;

/// Hits among `queries` (coefficients, lo, hi) by `solver`: one pass over the corpus.
fn hits<'a>(solver: Solver, queries: impl Iterator<Item = (&'a [f64], f64, f64)>) -> usize {
    queries
        .filter(|&(c, lo, hi)| solver.first_root(black_box(c), lo, hi).is_some())
        .count()
}

/// `queries` (coefficients, lo, hi) in groups of [`LANES`], as the lanes' query takes them.
type Groups<const D: usize> = Vec<([[f64; D]; LANES], [f64; LANES], [f64; LANES], [bool; LANES])>;

/// `queries` in groups of [`LANES`], each padded with zeros to `D` coefficients (a few
/// typed queries come with fewer: the same polynomial, the same answer); `None` when one has
/// more.
fn groups<'a, const D: usize>(
    queries: impl Iterator<Item = (&'a [f64], f64, f64)>,
) -> Option<Groups<D>> {
    let all: Vec<_> = queries.collect();
    all.chunks(LANES)
        .map(|group| {
            let mut out = (
                [[0.0; D]; LANES],
                [0.0; LANES],
                [1.0; LANES],
                [false; LANES],
            );
            for (l, &(c, lo, hi)) in group.iter().enumerate() {
                out.0[l].get_mut(..c.len())?.copy_from_slice(c);
                (out.1[l], out.2[l], out.3[l]) = (lo, hi, true);
            }
            Some(out)
        })
        .collect()
}

/// Hits among `groups` by `solver`'s lanes' query: one pass over the corpus.
fn lane_hits<const D: usize>(solver: Solver, groups: &Groups<D>) -> usize {
    groups
        .iter()
        .map(|(c, lo, hi, active)| {
            let found = solver.first_root_lanes(black_box(c), *lo, *hi, *active);
            found.iter().filter(|t| t.is_some()).count()
        })
        .sum()
}

fn bench(c: &mut Criterion) {
    let corpus = heart_corpus();
    let mut group = c.benchmark_group("first_root");
    group.throughput(Throughput::Elements(corpus.len() as u64));
    for &(solver, name) in Solver::ALL {
        group.bench_function(name, |b| {
            b.iter(|| hits(solver, corpus.iter().map(|r| (&r.coeffs[..], r.lo, r.hi))))
        });
    }
    let lanes = groups::<7>(corpus.iter().map(|r| (&r.coeffs[..], r.lo, r.hi))).expect("sextics");
    for &(solver, name) in Solver::ALL {
        group.bench_function(format!("lanes/{name}"), |b| {
            b.iter(|| lane_hits(solver, &lanes))
        });
    }
    group.finish();

    let typed = typed_corpus();
    let mut group = c.benchmark_group("first_root_typed");
    for (surface, degree) in TYPED_SURFACES {
        let rays: Vec<_> = typed.iter().filter(|r| r.surface == surface).collect();
        group.throughput(Throughput::Elements(rays.len() as u64));
        for &(solver, name) in Solver::ALL {
            group.bench_function(format!("degree {degree}/{name}"), |b| {
                b.iter(|| hits(solver, rays.iter().map(|r| (&r.coeffs[..], r.lo, r.hi))))
            });
        }
        let queries = || rays.iter().map(|r| (&r.coeffs[..], r.lo, r.hi));
        macro_rules! lanes_of_degree {
            ($($d:literal)*) => {
                match degree + 1 {
                    $($d => {
                        let lanes = groups::<$d>(queries()).expect("at most degree + 1 coefficients");
                        for &(solver, name) in Solver::ALL {
                            group.bench_function(format!("degree {degree}/lanes/{name}"), |b| {
                                b.iter(|| lane_hits(solver, &lanes))
                            });
                        }
                    })*
                    _ => {}
                }
            };
        }
        lanes_of_degree!(5 7 9 17);
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
