//! `first_root` on two fixed corpora, for every strategy: the heart's
//! (`kardia::shapes::heart::heart_corpus`: camera rays through an axis-aligned heart, each
//! restricted to its bounding box, hits and misses) and the typed surfaces'
//! (`kardia::shapes::implicit::typed_corpus`: the queries the generic implicit path puts to
//! the solver for camera rays through a torus, Barth's sextic, Chmutov's octic and a sphere
//! written with degree 16), one benchmark per degree. The throughput line gives calls per
//! second: ns per call = 1e9 / that.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
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

fn bench(c: &mut Criterion) {
    let corpus = heart_corpus();
    let mut group = c.benchmark_group("first_root");
    group.throughput(Throughput::Elements(corpus.len() as u64));
    for &(solver, name) in Solver::ALL {
        group.bench_function(name, |b| {
            b.iter(|| hits(solver, corpus.iter().map(|r| (&r.coeffs[..], r.lo, r.hi))))
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
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
