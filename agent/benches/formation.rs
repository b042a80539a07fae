//! Criterion benches of the formation kernels: one ORCA velocity (9 and 100 neighbours), the
//! Hungarian reassignment of eq. (15) (9, 100, 500 robots) and the pattern optimiser for 9
//! robots (with rotation, and the theta = 0 baseline).
//!
//! `cargo bench -p agent --bench formation`

use agent::formation::hungarian::{assign_targets, Hungarian};
use agent::formation::optimise::{optimise, optimise_without_rotation};
use agent::formation::orca::{orca_velocity, Disc};
use agent::formation::OptimiserBound;
use agent::formation::{FormationParams, Template};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Duration;
use swarm::geometry::Vec2;

fn points(rng: &mut ChaCha8Rng, n: usize, side: f64) -> Vec<Vec2> {
    (0..n)
        .map(|_| Vec2::new(rng.gen_range(0.0..side), rng.gen_range(0.0..side)))
        .collect()
}

/// `k` neighbours on a square lattice of pitch 2.5 around a robot at the origin, with random
/// velocities; the preferred velocity points across them.
fn orca_scene(k: usize) -> (Disc, Vec<Disc>) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let me = Disc {
        position: Vec2::zeros(),
        velocity: Vec2::new(0.5, 0.1),
        radius: 1.0,
    };
    let side = (k as f64 + 1.0).sqrt().ceil() as i64;
    let mut others = Vec::with_capacity(k);
    'grid: for gx in -side / 2..=side / 2 + 1 {
        for gy in -side / 2..=side / 2 + 1 {
            if others.len() == k {
                break 'grid;
            }
            if gx == 0 && gy == 0 {
                continue;
            }
            let v = Vec2::new(rng.gen_range(-0.7..0.7), rng.gen_range(-0.7..0.7));
            let position = Vec2::new(gx as f64 * 2.5, gy as f64 * 2.5);
            others.push(Disc {
                position,
                velocity: v,
                radius: 1.0,
            });
        }
    }
    (me, others)
}

fn bench_orca(c: &mut Criterion) {
    // Every neighbour counts (the paper's eq. 25 intersects over all robots).
    let params = FormationParams {
        neighbour_dist: 1e9,
        ..FormationParams::default()
    };
    let obstacles = [Disc {
        position: Vec2::new(6.0, -7.0),
        velocity: Vec2::zeros(),
        radius: 2.0,
    }];
    let mut g = c.benchmark_group("orca");
    for k in [9usize, 100] {
        let (me, others) = orca_scene(k);
        g.bench_with_input(BenchmarkId::new("velocity", k), &others, |b, others| {
            b.iter(|| {
                orca_velocity(
                    black_box(&me),
                    Vec2::new(1.0, 0.0),
                    black_box(others),
                    &obstacles,
                    &params,
                )
            })
        });
    }
    g.finish();
}

fn bench_hungarian(c: &mut Criterion) {
    let mut g = c.benchmark_group("hungarian");
    for n in [9usize, 100, 500] {
        let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
        let side = 2.5 * (n as f64).sqrt() * 2.0;
        let (p, q) = (points(&mut rng, n, side), points(&mut rng, n, side));
        let mut solver = Hungarian::new();
        let mut assignment = Vec::new();
        if n == 500 {
            g.sample_size(10);
        }
        g.bench_function(BenchmarkId::new("assign", n), |b| {
            b.iter(|| assign_targets(black_box(&p), black_box(&q), &mut solver, &mut assignment))
        });
    }
    g.finish();
}

fn bench_optimiser(c: &mut Criterion) {
    let params = FormationParams::default();
    let template = Template::letter_c();
    // Nine starts clear of each other and of the obstacles (seeded).
    let mut rng = ChaCha8Rng::seed_from_u64(1003);
    let obstacles: Vec<Vec2> = params
        .obstacle_centres
        .iter()
        .map(|c| Vec2::new(c[0], c[1]))
        .collect();
    let mut starts: Vec<Vec2> = Vec::new();
    while starts.len() < 9 {
        let p = Vec2::new(rng.gen_range(1.0..23.0), rng.gen_range(1.0..23.0));
        if starts.iter().all(|q| (p - q).norm() >= 2.1)
            && obstacles.iter().all(|o| (p - o).norm() >= 3.1)
        {
            starts.push(p);
        }
    }
    let mut g = c.benchmark_group("optimiser");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("with-rotation-9", |b| {
        b.iter(|| optimise(black_box(&starts), &template, &params).unwrap())
    });
    g.bench_function("without-rotation-9", |b| {
        b.iter(|| optimise_without_rotation(black_box(&starts), &template, &params).unwrap())
    });
    // The same solve with the interval-corner bound (params.rs `OptimiserBound`), beside the
    // alignment polygon (the default) in one run.
    let mut corners = params.clone();
    corners.optimiser.bound = OptimiserBound::Corners;
    g.bench_function("with-rotation-9-corners", |b| {
        b.iter(|| optimise(black_box(&starts), &template, &corners).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench_orca, bench_hungarian, bench_optimiser);
criterion_main!(benches);
