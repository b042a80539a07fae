//! Criterion benches of the search kernels' hot code: the target estimator (eqs. 7-10,
//! multi-start Nelder-Mead) and one BSOA obstacle-avoidance step (Table 2).
//!
//! `cargo bench -p search --bench kernels`

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use search::kernels::bsoa::{self, Sense as Sf};
use search::kernels::estimator::{self, Detection};
use swarm::geometry::{sample_boundary, Vec2};

/// `k` detectors on a ring around a target at (400, 300), distances with a small error.
fn detections(k: usize) -> Vec<Detection> {
    let target = Vec2::new(400.0, 300.0);
    (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64 + 0.3;
            let r = 40.0 + 7.0 * i as f64;
            let position = target + Vec2::new(r * a.cos(), r * a.sin());
            Detection {
                position,
                distance: r * (1.0 + 0.01 * ((i % 3) as f64 - 1.0)),
                signal: 1.0 / (1.0 + r),
            }
        })
        .collect()
}

fn bench_estimator(c: &mut Criterion) {
    let p = estimator::Params::default();
    let mut g = c.benchmark_group("estimator");
    for k in [3usize, 5, 10] {
        let d = detections(k);
        g.bench_with_input(BenchmarkId::new("estimate", k), &d, |b, d| {
            b.iter(|| estimator::estimate(black_box(d), &p))
        });
    }
    g.finish();
}

/// Obstacle points a robot at `x` senses within `range` (boundary sampled every 2 units).
fn sensed(polys: &[Vec<Vec2>], x: &Vec2, range: f64) -> Vec<Vec2> {
    polys
        .iter()
        .flat_map(|p| sample_boundary(p, 2.0))
        .filter(|q| (q - x).norm() < range)
        .collect()
}

fn bench_bsoa(c: &mut Criterion) {
    let p = bsoa::Params::default();
    let block = vec![
        Vec2::new(300.0, 200.0),
        Vec2::new(420.0, 230.0),
        Vec2::new(400.0, 330.0),
        Vec2::new(290.0, 310.0),
    ];
    let u_trap = vec![
        Vec2::new(550.0, 500.0),
        Vec2::new(700.0, 500.0),
        Vec2::new(700.0, 650.0),
        Vec2::new(670.0, 650.0),
        Vec2::new(670.0, 530.0),
        Vec2::new(580.0, 530.0),
        Vec2::new(580.0, 650.0),
        Vec2::new(550.0, 650.0),
    ];
    let cases = [
        // Heading straight at the block's face from 30 units away.
        (
            "block-ahead",
            vec![block.clone()],
            Vec2::new(260.0, 260.0),
            Vec2::new(10.0, 0.0),
        ),
        // Inside the U, heading into its closed end.
        (
            "u-trap",
            vec![u_trap.clone()],
            Vec2::new(625.0, 600.0),
            Vec2::new(0.0, -10.0),
        ),
        // Obstacles in range but not ahead: the free case after the scan of the points.
        (
            "free",
            vec![block],
            Vec2::new(260.0, 260.0),
            Vec2::new(-10.0, 0.0),
        ),
    ];
    let mut g = c.benchmark_group("bsoa");
    for (name, polys, x, v) in cases {
        let pts = sensed(&polys, &x, p.l_b);
        g.bench_function(
            BenchmarkId::new("avoid", format!("{name}-{}pts", pts.len())),
            |b| b.iter(|| bsoa::avoid(black_box(&x), black_box(&v), black_box(&pts), Sf::None, &p)),
        );
    }
    g.finish();
}

criterion_group!(benches, bench_estimator, bench_bsoa);
criterion_main!(benches);
