//! Criterion bench of CBCA's Algorithm 1 (bundle construction, thesis sec. 4.2.2): one robot
//! building its bundle from empty beliefs on Example 1 (4 targets), and on a generated 30-target
//! field (the n_e of Fig. 4.6) with l_i = 3.
//!
//! `cargo bench -p agent --bench cbca`

use agent::cbca::bundle::{build_bundle, Plan, StaticPeers};
use agent::cbca::scenario::CbcaScenario;
use agent::cbca::winners::Winners;
use agent::cbca::{Robot, Task, TaskBook};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn example1() -> (Vec<Robot>, TaskBook, CbcaScenario) {
    let s = CbcaScenario::from_toml(include_str!("../../configs/hunt-cbca-example1.toml"))
        .expect("example 1 parses");
    (s.robots().unwrap(), s.task_book().unwrap(), s)
}

/// `n` targets uniform in the 10 km arena, table-like values.
fn field(n: usize, seed: u64) -> TaskBook {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|j| {
            let mut required = [0.0; 6];
            for r in &mut required {
                *r = rng.gen_range(5.0..18.0_f64).round();
            }
            let t = Task {
                id: j,
                position: [rng.gen_range(0.0..10.0), rng.gen_range(0.0..10.0)],
                value: rng.gen_range(100.0..600.0),
                required,
                beta: rng.gen_range(0.45..0.71),
                robots_needed: rng.gen_range(3..=4),
                hold_time: 1.0,
            };
            (j, t)
        })
        .collect()
}

fn bench_bundle(c: &mut Criterion) {
    let (robots, book1, s) = example1();
    let peers = StaticPeers {
        resources: robots.iter().map(|r| r.resources).collect(),
        paths: vec![vec![]; robots.len()],
    };
    let mut g = c.benchmark_group("cbca_bundle");
    for (name, book) in [("example1", book1), ("n_e=30", field(30, 1))] {
        g.bench_with_input(BenchmarkId::from_parameter(name), &book, |b, book| {
            b.iter(|| {
                let mut plan = Plan::default();
                let mut winners = Winners::new(robots.len(), book.len());
                black_box(build_bundle(
                    &robots[2],
                    &mut plan,
                    &mut winners,
                    book,
                    &peers,
                    &s.params,
                ))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_bundle);
criterion_main!(benches);
