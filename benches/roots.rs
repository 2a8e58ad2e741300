//! `first_root` on the shared heart ray corpus (`kardia::shapes::heart::heart_corpus`: camera rays
//! through an axis-aligned heart, each restricted to its bounding box, hits and misses), for
//! every strategy. The throughput line gives calls per second: ns per call = 1e9 / that.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use kardia::roots::Solver;
use kardia::shapes::heart::heart_corpus;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let corpus = heart_corpus();
    let mut group = c.benchmark_group("first_root");
    group.throughput(Throughput::Elements(corpus.len() as u64));
    for &(solver, name) in Solver::ALL {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut hits = 0usize;
                for r in &corpus {
                    if solver
                        .first_root(black_box(&r.coeffs), r.lo, r.hi)
                        .is_some()
                    {
                        hits += 1;
                    }
                }
                hits
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
