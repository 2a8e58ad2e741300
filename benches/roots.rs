//! Root-finder micro-benchmark (filled in by the roots work).
use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let coeffs = kardia::shapes::heart::sextic_coefficients(
        glam::DVec3::new(5.0, 0.1, 0.2),
        glam::DVec3::new(-1.0, 0.0, 0.0),
    );
    c.bench_function("first_root", |b| {
        b.iter(|| kardia::roots::first_root(std::hint::black_box(&coeffs), 0.0, 10.0))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
