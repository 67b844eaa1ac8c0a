//! Host cost of one snapshot solve (paper 002) and of one solve with integer ambiguity search
//! (criterion). The target's instruction counts of the same calls come from the firmware under
//! `examples/firmware` (printed by `.ci/run`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use gnss_attitude::attitude::example;

fn bench(c: &mut Criterion) {
    let solver = example::solver().unwrap_or_else(|e| panic!("{e}"));
    let resolver = example::resolver().unwrap_or_else(|e| panic!("{e}"));
    let three = example::ranges(3, 1).unwrap_or_else(|e| panic!("{e}"));
    let eight = example::ranges(8, 1).unwrap_or_else(|e| panic!("{e}"));
    let phases = example::phases(8, 1).unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("snapshot_solve_3sat", |b| {
        b.iter(|| black_box(solver.solve(black_box(&three))).ok());
    });
    c.bench_function("snapshot_solve_8sat", |b| {
        b.iter(|| black_box(solver.solve(black_box(&eight))).ok());
    });
    c.bench_function("ambiguity_resolve_8sat", |b| {
        b.iter(|| black_box(resolver.resolve(black_box(&phases))).ok());
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
