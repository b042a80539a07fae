use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random centred instance: (n, dot, cross, every permutation's z).
struct Instance {
    n: usize,
    dot: Vec<f64>,
    cross: Vec<f64>,
}

impl Instance {
    fn random(n: usize, rng: &mut ChaCha8Rng) -> Self {
        let centred = |rng: &mut ChaCha8Rng| {
            let v: Vec<Vec2> = (0..n)
                .map(|_| Vec2::new(rng.gen_range(-5.0..5.0), rng.gen_range(-5.0..5.0)))
                .collect();
            let m = v.iter().sum::<Vec2>() / n as f64;
            v.into_iter().map(|x| x - m).collect::<Vec<_>>()
        };
        let (p, s) = (centred(rng), centred(rng));
        let (dot, cross) = alignment_matrices(&p, &s);
        Self { n, dot, cross }
    }

    fn scale(&self) -> f64 {
        let n = self.n;
        let p2: f64 = (0..n).map(|i| self.dot[i * n + i].abs()).sum::<f64>() + 1.0;
        p2 * 100.0
    }

    /// z(sigma) of every permutation (n <= 7).
    fn all_z(&self) -> Vec<Vec2> {
        let n = self.n;
        let mut out = Vec::new();
        crate::formation::test_support::for_each_permutation(n, |p| {
            out.push(p.iter().enumerate().fold(Vec2::zeros(), |z, (i, &j)| {
                z + Vec2::new(self.dot[i * n + j], self.cross[i * n + j])
            }));
        });
        out
    }
}

fn oracle<'a>(inst: &'a Instance, h: &'a mut Hungarian) -> MatrixOracle<'a> {
    MatrixOracle {
        n: inst.n,
        dot: &inst.dot,
        cross: &inst.cross,
        hungarian: h,
        work: 0.0,
    }
}

fn support(zs: &[Vec2], u: Vec2) -> f64 {
    zs.iter()
        .map(|z| u.dot(z))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The true min over a dense grid of the rectangle (|A| >= lambda) of S2 |A|^2 - 2 h(A).
fn grid_min(zs: &[Vec2], ar: [f64; 2], br: [f64; 2], s2: f64, lambda: f64) -> f64 {
    let k = 60;
    let mut best = f64::INFINITY;
    for ia in 0..=k {
        for ib in 0..=k {
            let a = Vec2::new(
                ar[0] + (ar[1] - ar[0]) * ia as f64 / k as f64,
                br[0] + (br[1] - br[0]) * ib as f64 / k as f64,
            );
            if a.norm() >= lambda {
                best = best.min(s2 * a.norm_squared() - 2.0 * support(zs, a));
            }
        }
    }
    best
}

#[test]
fn traced_polygon_is_the_hull_of_every_permutation() {
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    for n in 2..=7 {
        for _ in 0..8 {
            let inst = Instance::random(n, &mut rng);
            let zs = inst.all_z();
            let mut h = Hungarian::new();
            let mut o = oracle(&inst, &mut h);
            let mut poly = AlignmentPolygon::new(&mut o, inst.scale(), (usize::MAX, 1e18), true);
            poly.trace_all(&mut o);
            assert!(poly.complete());
            for _ in 0..200 {
                let phi = rng.gen_range(0.0..TAU);
                let u = dir(phi);
                let (z, sigma) = poly.assignment_at(u.x, u.y, &mut o);
                let z_of_sigma = sigma.iter().enumerate().fold(Vec2::zeros(), |z, (i, &j)| {
                    z + Vec2::new(inst.dot[i * n + j], inst.cross[i * n + j])
                });
                assert!((z - z_of_sigma).norm() < 1e-9);
                let truth = support(&zs, u);
                assert!(
                    (u.dot(&z) - truth).abs() < 1e-9,
                    "n {n}: {} vs {truth}",
                    u.dot(&z)
                );
            }
            // Each vertex is optimal on an arc; a traced H needs about 2 solves a vertex.
            let distinct = poly.samples();
            assert!(
                poly.solves() <= 2 * distinct + 4,
                "{} solves",
                poly.solves()
            );
        }
    }
}

#[test]
fn bound_is_valid_and_tight_on_random_rectangles_with_and_without_budget() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    for n in 3..=6 {
        let inst = Instance::random(n, &mut rng);
        let zs = inst.all_z();
        let s2 = rng.gen_range(20.0..200.0);
        for budget in [4, 6, usize::MAX] {
            let mut h = Hungarian::new();
            let mut o = oracle(&inst, &mut h);
            let mut poly = AlignmentPolygon::new(&mut o, inst.scale(), (budget, 1e18), budget != 6);
            for _ in 0..40 {
                let (a0, b0) = (rng.gen_range(-2.5..2.5), rng.gen_range(-2.5..2.5));
                let (wa, wb) = (rng.gen_range(0.0..1.5), rng.gen_range(0.0..1.5));
                let (ar, br) = ([a0, a0 + wa], [b0, b0 + wb]);
                let lambda = if rng.gen_bool(0.3) { 1.0 } else { 0.0 };
                let truth = grid_min(&zs, ar, br, s2, lambda);
                if !truth.is_finite() {
                    continue;
                }
                let bound = poly.quad_bound(ar, br, s2, lambda, &mut o);
                assert!(bound <= truth + 1e-9, "budget {budget}: {bound} > {truth}");
                if budget == usize::MAX && lambda == 0.0 {
                    // Exact: below the grid by at most the grid step times the gradient.
                    let a_max = (a0.abs() + wa).hypot(b0.abs() + wb);
                    let z_max = zs.iter().map(|z| z.norm()).fold(0.0, f64::max);
                    let step = (wa.max(wb) / 60.0) * std::f64::consts::SQRT_2;
                    let slack = step * (2.0 * s2 * a_max + 2.0 * z_max) + 1e-9;
                    assert!(
                        bound >= truth - slack,
                        "{bound} far below {truth} ({slack})"
                    );
                }
            }
        }
    }
}

#[test]
fn warm_started_solves_find_the_cold_optimum() {
    let mut rng = ChaCha8Rng::seed_from_u64(45);
    for n in [5, 20, 60] {
        let inst = Instance::random(n, &mut rng);
        let mut h = Hungarian::new();
        let (mut sigma, mut v) = (Vec::new(), Vec::new());
        let mut o = oracle(&inst, &mut h);
        let mut phi = rng.gen_range(0.0..TAU);
        o.best(phi, None, &mut sigma, &mut v);
        for _ in 0..50 {
            phi += rng.gen_range(-0.3..0.3);
            let (mut cold, mut vc) = (Vec::new(), Vec::new());
            let zc = o.best(phi, None, &mut cold, &mut vc);
            let (mut warm, mut vw) = (Vec::new(), Vec::new());
            let zw = o.best(phi, Some((&sigma, &v)), &mut warm, &mut vw);
            let u = dir(phi);
            assert!((u.dot(&zc) - u.dot(&zw)).abs() < 1e-9, "n {n}");
            let mut seen = vec![false; n];
            assert!(warm.iter().all(|&j| !std::mem::replace(&mut seen[j], true)));
            (sigma, v) = (warm, vw);
        }
    }
}

#[test]
fn angular_range_covers_the_rectangle() {
    let mut rng = ChaCha8Rng::seed_from_u64(43);
    for _ in 0..2000 {
        let (a0, b0) = (rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0));
        let (ar, br) = (
            [a0, a0 + rng.gen_range(0.0..1.0)],
            [b0, b0 + rng.gen_range(0.0..1.0)],
        );
        match angular_range(ar, br) {
            None => assert!(ar[0] <= 0.0 && ar[1] >= 0.0 && br[0] <= 0.0 && br[1] >= 0.0),
            Some((lo, hi)) => {
                assert!((0.0..TAU).contains(&lo) && hi >= lo && hi - lo < PI);
                for _ in 0..20 {
                    let a = rng.gen_range(ar[0]..=ar[1]);
                    let b = rng.gen_range(br[0]..=br[1]);
                    let mut phi = b.atan2(a).rem_euclid(TAU);
                    if phi < lo - 1e-12 {
                        phi += TAU;
                    }
                    assert!(
                        phi >= lo - 1e-12 && phi <= hi + 1e-12,
                        "{phi} not in {lo}..{hi}"
                    );
                }
            }
        }
    }
}

/// Measurement, not a check: `cargo test --release -p agent trace_cost -- --ignored
/// --nocapture`. Cold and warm-started traces side by side, capped at 600 solves.
#[test]
#[ignore]
fn trace_cost() {
    let mut rng = ChaCha8Rng::seed_from_u64(44);
    for n in [9, 30, 100, 500] {
        let inst = Instance::random(n, &mut rng);
        let mut results = Vec::new();
        for warm in [false, true] {
            let mut h = Hungarian::new();
            let mut o = oracle(&inst, &mut h);
            let t = std::time::Instant::now();
            let mut poly = AlignmentPolygon::new(&mut o, inst.scale(), (600, 1e18), warm);
            poly.trace_all(&mut o);
            let z: Vec<Vec2> = poly.samples.iter().map(|s| s.z).collect();
            eprintln!(
                "n {n} warm {warm}: {} vertices, {} solves, complete {}, {:.3} s",
                poly.samples(),
                poly.solves(),
                poly.complete(),
                t.elapsed().as_secs_f64()
            );
            results.push(z);
        }
        let same = results[0].len() == results[1].len()
            && results[0]
                .iter()
                .zip(&results[1])
                .all(|(a, b)| (a - b).norm() < 1e-6 * (1.0 + a.norm()));
        eprintln!("n {n}: same vertices cold and warm: {same}");
    }
}
