//! Criterion bench of the hunting kernels: one improved auction (thesis sec. 3.1-3.2) and one
//! parallel auction on a random instance of the chapter 3 sweeps, n_e = 12 tasks, n_r = 30 robots.
//!
//! `cargo bench -p agent --bench hunt`

use agent::hunt::auction::run_auction;
use agent::hunt::instance::{random_instance, InstanceParams};
use agent::hunt::parallel_auction::run_parallel_auction;
use agent::hunt::HuntParams;
use criterion::{black_box, criterion_group, criterion_main, Criterion};

fn bench_auctions(c: &mut Criterion) {
    let p = HuntParams::default();
    let (tasks, robots) = random_instance(12, 30, 1, &InstanceParams::default());
    let out = run_auction(&tasks, &robots, &p);
    eprintln!(
        "instance: {} rounds, {} of 12 tasks awarded, finish {:?}",
        out.rounds.len(),
        out.coalitions.len(),
        out.finish
    );
    let mut g = c.benchmark_group("hunt_auction");
    g.bench_function("improved_ne12_nr30", |b| {
        b.iter(|| run_auction(black_box(&tasks), black_box(&robots), &p))
    });
    g.bench_function("parallel_ne12_nr30", |b| {
        b.iter(|| run_parallel_auction(black_box(&tasks), black_box(&robots), &p))
    });
    g.finish();
}

criterion_group!(benches, bench_auctions);
criterion_main!(benches);
