//! Criterion benchmarks: 10 s of the R2 random test per model, and one paper-program test.

use criterion::{criterion_group, criterion_main, Criterion};
use shaketable::benchmark::{models, random_inputs};
use shaketable::solver::{simulate_record, DEFAULT_MAX_SUBSTEP_S};
use shaketable::Model;

fn simulate(c: &mut Criterion) {
    let inputs = random_inputs(10.0);
    let mut group = c.benchmark_group("simulate 10 s of R2");
    group.sample_size(20);
    for (name, params) in models() {
        let model = Model::new(&params);
        group.bench_function(name, |b| {
            b.iter(|| simulate_record(&model, &inputs, 512.0, None, DEFAULT_MAX_SUBSTEP_S))
        });
    }
    group.finish();
}

criterion_group!(benches, simulate);
criterion_main!(benches);
