//! The alignment polygon: every assignment the pattern optimiser can ever need, traced once.
//!
//! In the centred objective of [`super::optimise`], g(a, b, sigma) = P2 + |A|^2 S2 -
//! 2 A . z(sigma) with A = (a, b) and z(sigma) = (D(sigma), X(sigma)), the assignment enters only
//! through h(A) = max_sigma A . z(sigma), the support function of the convex polygon
//! H = conv{z(sigma)} (eq. 7's assignment step: for a fixed transform the Hungarian method
//! returns the z(sigma) of H farthest in the direction A). h is positively homogeneous, so the
//! optimal sigma depends only on the DIRECTION of A: the whole search over (alpha, theta) needs
//! only the vertices of H, one per arc of directions (its normal cone), and they can be traced
//! by the Hungarian method alone (the support-function outer approximation of a convex set
//! known only by its linear oracle, as in Eisner and Severance's parametric method):
//!
//! - solve at a few directions; two neighbouring directions phi_1 < phi_2 (less than pi apart)
//!   with vertices z_1 != z_2 leave between them an OPEN arc: H's boundary there lies inside the
//!   triangle z_1, z_2, w, where w is the apex where the supporting lines u_1 . z = h(u_1) and
//!   u_2 . z = h(u_2) meet, so h(u) <= u . w for every u between u_1 and u_2 (u = l u_1 + m u_2
//!   with l, m >= 0);
//! - refining it solves at the normal u of the segment z_1 z_2: if nothing beats u . z_1 the
//!   segment is an edge of H and the arc is CLOSED (h(u) = max(u . z_1, u . z_2) on it);
//!   otherwise the new vertex splits the arc in two open ones.
//!
//! The optimiser's lower bound over an (a, b) rectangle R (module comment of optimise.rs) then
//! becomes exact in the assignment: min over A in R of S2 |A|^2 - 2 h(A) equals the minimum,
//! over the candidates c of the arcs that R's directions meet (the two vertices of a closed arc,
//! the apex of an open one), of min over A in R of S2 |A|^2 - 2 A . c (each candidate's
//! quadratic is >= the true one where h(A) <= A . c, and the true minimiser's own vertex gives
//! equality). An open arc whose apex gives the minimum is refined (one Hungarian solve) while
//! the solve budget lasts, so every bound a node gets is exact once its arcs are traced, and a
//! node costs no Hungarian solve at all once they are: with H's V vertices, the whole search
//! makes at most about 2V solves, against five to six per node for the interval-corner bounds
//! (`OptimiserBound::Corners`, kept beside it).

use super::hungarian::Hungarian;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use swarm::geometry::Vec2;

/// The linear oracle: the assignment maximising A . z(sigma) for the direction A = (cos phi,
/// sin phi), written to `sigma`, and its z(sigma) = (D(sigma), X(sigma)).
pub trait AlignmentOracle {
    /// Solve at direction angle `phi` (one Hungarian solve), warm-started from a nearby
    /// direction's (sigma, column potentials) when given; the solve's column potentials go to
    /// `potentials`.
    fn best(
        &mut self,
        phi: f64,
        warm: Option<(&[usize], &[f64])>,
        sigma: &mut Vec<usize>,
        potentials: &mut Vec<f64>,
    ) -> Vec2;

    /// The operations the last solve took, counting n^2 for each augmented row and for the
    /// cost matrix (a cold n x n solve: about n^3).
    fn last_work(&self) -> f64;
}

/// The oracle of centred starts and template: dot\[i n + j\] = p~_i . s~_j and cross\[i n + j\]
/// = s~_j x p~_i, so that A . z(sigma) = sum_i a dot\[i, sigma(i)\] + b cross\[i, sigma(i)\].
pub struct MatrixOracle<'a> {
    pub n: usize,
    pub dot: &'a [f64],
    pub cross: &'a [f64],
    pub hungarian: &'a mut Hungarian,
    /// The last solve's operations ([`AlignmentOracle::last_work`]).
    pub work: f64,
}

impl AlignmentOracle for MatrixOracle<'_> {
    fn last_work(&self) -> f64 {
        self.work
    }

    fn best(
        &mut self,
        phi: f64,
        warm: Option<(&[usize], &[f64])>,
        sigma: &mut Vec<usize>,
        potentials: &mut Vec<f64>,
    ) -> Vec2 {
        let (b, a) = phi.sin_cos();
        let (n, dot, cross) = (self.n, self.dot, self.cross);
        let cost = |i: usize, j: usize| -(a * dot[i * n + j] + b * cross[i * n + j]);
        match warm {
            Some(w) => self.hungarian.solve_warm_with(n, cost, w, sigma),
            None => self.hungarian.solve_with(n, cost, sigma),
        };
        potentials.clear();
        potentials.extend_from_slice(self.hungarian.column_potentials());
        self.work = (n * n) as f64 * (1 + self.hungarian.augmented_rows()) as f64;
        sigma.iter().enumerate().fold(Vec2::zeros(), |z, (i, &j)| {
            z + Vec2::new(dot[i * n + j], cross[i * n + j])
        })
    }
}

/// The oracle's matrices of centred starts p~ and template s~: dot\[i n + j\] = p~_i . s~_j
/// and cross\[i n + j\] = s~_j x p~_i (2-D cross product).
pub fn alignment_matrices(p_tilde: &[Vec2], s_tilde: &[Vec2]) -> (Vec<f64>, Vec<f64>) {
    let n = p_tilde.len();
    let mut dot = vec![0.0; n * n];
    let mut cross = vec![0.0; n * n];
    for (i, p) in p_tilde.iter().enumerate() {
        for (j, s) in s_tilde.iter().enumerate() {
            dot[i * n + j] = p.dot(s);
            cross[i * n + j] = s.x * p.y - s.y * p.x;
        }
    }
    (dot, cross)
}

/// A direction solved exactly: the vertex z of H that is optimal there, and its sigma.
#[derive(Debug, Clone)]
struct Sample {
    /// Direction angle in \[0, 2 pi).
    phi: f64,
    z: Vec2,
    sigma: Vec<usize>,
    /// The solve's column potentials (to warm-start a solve at a nearby direction).
    potentials: Vec<f64>,
}

/// H, traced as far as the optimiser needed it.
#[derive(Debug, Clone)]
pub struct AlignmentPolygon {
    /// Sorted by `phi`; the first is at phi = 0 and is never removed.
    samples: Vec<Sample>,
    /// `closed[i]`: the arc from sample i to sample i + 1 (the last: to the first, + 2 pi) is
    /// fully known (one vertex, or an edge of H).
    closed: Vec<bool>,
    /// Hungarian solves made.
    solves: usize,
    /// Solves allowed; beyond them open arcs stay open (their apexes keep the bound valid).
    max_solves: usize,
    /// Operations spent ([`AlignmentOracle::last_work`] summed) and allowed.
    work: f64,
    max_work: f64,
    /// Two vertices closer than this are one; an improvement below it confirms an edge.
    tol: f64,
    /// Warm-start each solve from the arc's first sample (`OptimiserParams::warm_start`).
    warm: bool,
}

/// A bound's candidate point: a vertex, or the apex of the open arc `arc`.
#[derive(Debug, Clone, Copy)]
enum Candidate {
    Vertex(Vec2),
    Apex { arc: usize, w: Vec2 },
}

impl AlignmentPolygon {
    /// Solve at the four axis directions. `scale` bounds |z| (sqrt(P2 S2) does, by
    /// Cauchy-Schwarz) and sets the tolerance; `max_solves` (at least 4 are made) caps the
    /// refinement.
    pub fn new(
        oracle: &mut impl AlignmentOracle,
        scale: f64,
        (max_solves, max_work): (usize, f64),
        warm: bool,
    ) -> Self {
        let mut work = 0.0;
        let mut samples: Vec<Sample> = Vec::with_capacity(64);
        for k in 0..4 {
            let phi = k as f64 * FRAC_PI_2;
            let (mut sigma, mut potentials) = (Vec::new(), Vec::new());
            let from = samples
                .last()
                .filter(|_| warm)
                .map(|s| (&s.sigma[..], &s.potentials[..]));
            let z = oracle.best(phi, from, &mut sigma, &mut potentials);
            work += oracle.last_work();
            samples.push(Sample {
                phi,
                z,
                sigma,
                potentials,
            });
        }
        let mut polygon = Self {
            closed: vec![false; 4],
            samples,
            solves: 4,
            max_solves,
            work,
            max_work,
            tol: 1e-11 * scale.max(1e-300),
            warm,
        };
        for i in 0..4 {
            polygon.closed[i] = polygon.same(i, (i + 1) % 4);
        }
        polygon
    }

    /// Hungarian solves made so far.
    pub fn solves(&self) -> usize {
        self.solves
    }

    /// Operations spent so far ([`AlignmentOracle::last_work`]).
    pub fn work(&self) -> f64 {
        self.work
    }

    fn budget_left(&self) -> bool {
        self.solves < self.max_solves && self.work < self.max_work
    }

    /// The tolerance of vertex equality and edge confirmation (the bound subtracts its effect).
    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    /// Vertices traced so far (distinct or not).
    pub fn samples(&self) -> usize {
        self.samples.len()
    }

    /// Whether every arc is closed: H is known exactly.
    pub fn complete(&self) -> bool {
        self.closed.iter().all(|&c| c)
    }

    fn same(&self, i: usize, k: usize) -> bool {
        (self.samples[i].z - self.samples[k].z).norm() <= self.tol
    }

    /// Arc i's end angle, unwrapped (> its start).
    fn arc_end(&self, i: usize) -> f64 {
        if i + 1 < self.samples.len() {
            self.samples[i + 1].phi
        } else {
            TAU
        }
    }

    fn next(&self, i: usize) -> usize {
        (i + 1) % self.samples.len()
    }

    /// The apex of open arc i: where the supporting lines at its two ends meet.
    fn apex(&self, i: usize) -> Vec2 {
        let (s, e) = (&self.samples[i], &self.samples[self.next(i)]);
        let (u1, u2) = (dir(s.phi), dir(e.phi));
        let (h1, h2) = (u1.dot(&s.z), u2.dot(&e.z));
        // Solve u1 . w = h1, u2 . w = h2 (Cramer); the arc is shorter than pi, so det > 0.
        let det = u1.x * u2.y - u1.y * u2.x;
        if det > 1e-9 {
            return Vec2::new((h1 * u2.y - h2 * u1.y) / det, (u1.x * h2 - u2.x * h1) / det);
        }
        // A tiny arc (Cramer ill-conditioned): for u at angle psi into an arc of width delta,
        // u = l u1 + m u2 with l + m = cos(delta / 2 - psi) / cos(delta / 2), so h(u) <=
        // (l + m) max(h1, h2) = u . c for c = u_mid max(h1, h2) / cos(delta / 2) (h >= 0: the
        // mean of z over all permutations is 0, so 0 is in H).
        let delta = self.arc_end(i) - s.phi;
        let mid = dir(s.phi + 0.5 * delta);
        mid * (h1.max(h2).max(0.0) / (0.5 * delta).cos())
    }

    /// The arc containing angle phi in \[0, 2 pi).
    fn arc_at(&self, phi: f64) -> usize {
        self.samples.partition_point(|s| s.phi <= phi).max(1) - 1
    }

    /// Refine open arc i by one solve at its edge normal. False when the budget is spent.
    fn refine(&mut self, i: usize, oracle: &mut impl AlignmentOracle) -> bool {
        if !self.budget_left() {
            return false;
        }
        let k = self.next(i);
        let (start, end) = (self.samples[i].phi, self.arc_end(i));
        let e = self.samples[k].z - self.samples[i].z;
        let mut phi = (-e.x).atan2(e.y).rem_euclid(TAU);
        if phi < start {
            phi += TAU;
        }
        if !(phi > start && phi < end) {
            phi = 0.5 * (start + end);
        }
        let (z, sigma, potentials) = self.solve_near(i, phi.rem_euclid(TAU), oracle);
        let u = dir(phi);
        let known = u.dot(&self.samples[i].z).max(u.dot(&self.samples[k].z));
        if u.dot(&z) <= known + self.tol {
            self.closed[i] = true;
        } else {
            self.insert(i, phi, z, sigma, potentials);
        }
        true
    }

    /// One solve at `phi`, warm-started from sample i when `warm`.
    fn solve_near(
        &mut self,
        i: usize,
        phi: f64,
        oracle: &mut impl AlignmentOracle,
    ) -> (Vec2, Vec<usize>, Vec<f64>) {
        let (mut sigma, mut potentials) = (Vec::new(), Vec::new());
        let s = &self.samples[i];
        let from = Some((&s.sigma[..], &s.potentials[..])).filter(|_| self.warm);
        let z = oracle.best(phi, from, &mut sigma, &mut potentials);
        self.solves += 1;
        self.work += oracle.last_work();
        (z, sigma, potentials)
    }

    /// Insert a solved direction inside arc i (phi unwrapped within it).
    fn insert(&mut self, i: usize, phi: f64, z: Vec2, sigma: Vec<usize>, potentials: Vec<f64>) {
        let at = i + 1;
        self.samples.insert(
            at,
            Sample {
                phi: phi.rem_euclid(TAU).min(TAU - f64::EPSILON * TAU),
                z,
                sigma,
                potentials,
            },
        );
        self.closed.insert(at, false);
        self.closed[i] = self.same(i, at);
        let k = self.next(at);
        self.closed[at] = self.same(at, k);
    }

    /// Refine every open arc until H is known exactly or the budget is spent.
    pub fn trace_all(&mut self, oracle: &mut impl AlignmentOracle) {
        let mut i = 0;
        while i < self.samples.len() {
            if self.closed[i] {
                i += 1;
            } else if !self.refine(i, oracle) {
                return;
            }
        }
    }

    /// Lower bound on min over A in the rectangle ar x br with |A| >= `lambda_min` of
    /// S2 |A|^2 - 2 h(A), refining the arcs it draws on while the budget lasts.
    pub fn quad_bound(
        &mut self,
        ar: [f64; 2],
        br: [f64; 2],
        s2: f64,
        lambda_min: f64,
        oracle: &mut impl AlignmentOracle,
    ) -> f64 {
        let a_max = ar[0]
            .abs()
            .max(ar[1].abs())
            .hypot(br[0].abs().max(br[1].abs()));
        // An edge confirmed within tol may hide a vertex at most tol beyond it (module tests).
        let safety = 2.0 * self.tol * a_max;
        let range = angular_range(ar, br);
        loop {
            let (value, best) = self.min_candidate(range, ar, br, s2, lambda_min);
            match best {
                Some(Candidate::Apex { arc, .. }) if self.refine(arc, oracle) => continue,
                _ => return value - safety,
            }
        }
    }

    /// min over the candidates of the arcs meeting `range` (None: every arc) of the quadratic.
    fn min_candidate(
        &self,
        range: Option<(f64, f64)>,
        ar: [f64; 2],
        br: [f64; 2],
        s2: f64,
        lambda_min: f64,
    ) -> (f64, Option<Candidate>) {
        let quad = |c: Vec2| {
            // S2 |A|^2 - 2 A . c = S2 (|A - y|^2 - |y|^2), y = c / S2; over the rectangle
            // |A - y| is at least the distance to it, and with |A| >= lambda_min at least
            // lambda_min - |y|.
            let y = c / s2;
            let dx = y.x - y.x.clamp(ar[0], ar[1]);
            let dy = y.y - y.y.clamp(br[0], br[1]);
            let to_sep = (lambda_min - y.norm()).max(0.0);
            s2 * ((dx * dx + dy * dy).max(to_sep * to_sep) - y.norm_squared())
        };
        let mut best = (f64::INFINITY, None);
        let consider = |c: Candidate, best: &mut (f64, Option<Candidate>)| {
            let v = match c {
                Candidate::Vertex(z) => quad(z),
                Candidate::Apex { w, .. } => quad(w),
            };
            if v < best.0 {
                *best = (v, Some(c));
            }
        };
        let m = self.samples.len();
        let (first, count) = match range {
            None => (0, m),
            Some((lo, hi)) => {
                let first = self.arc_at(lo);
                // Walk arcs while their start (unwrapped past the first) is before hi.
                let mut count = 0;
                while count < m {
                    let idx = first + count;
                    let start = self.samples[idx % m].phi + TAU * (idx / m) as f64;
                    if count > 0 && start > hi {
                        break;
                    }
                    count += 1;
                }
                (first, count)
            }
        };
        for step in 0..count {
            let i = (first + step) % m;
            if self.closed[i] {
                consider(Candidate::Vertex(self.samples[i].z), &mut best);
                consider(Candidate::Vertex(self.samples[self.next(i)].z), &mut best);
            } else {
                consider(
                    Candidate::Apex {
                        arc: i,
                        w: self.apex(i),
                    },
                    &mut best,
                );
            }
        }
        best
    }

    /// An assignment optimal (or, with the budget spent, the better of the arc's two traced
    /// ones) at the transform matrix A = (a, b), and its z. Solves when A's arc is open.
    pub fn assignment_at(
        &mut self,
        a: f64,
        b: f64,
        oracle: &mut impl AlignmentOracle,
    ) -> (Vec2, &[usize]) {
        if a == 0.0 && b == 0.0 {
            // h(0) = 0: every sigma is optimal.
            return (self.samples[0].z, &self.samples[0].sigma);
        }
        let phi = b.atan2(a).rem_euclid(TAU);
        let i = self.arc_at(phi);
        let k = self.next(i);
        let u = dir(phi);
        let endpoints = |p: &Self| {
            if u.dot(&p.samples[i].z) >= u.dot(&p.samples[k].z) {
                i
            } else {
                k
            }
        };
        let pick = if self.closed[i] || phi == self.samples[i].phi {
            endpoints(self)
        } else if self.budget_left() {
            let (z, sigma, potentials) = self.solve_near(i, phi, oracle);
            self.insert(i, phi, z, sigma, potentials);
            i + 1
        } else {
            endpoints(self)
        };
        let s = &self.samples[pick];
        (s.z, &s.sigma)
    }
}

fn dir(phi: f64) -> Vec2 {
    let (s, c) = phi.sin_cos();
    Vec2::new(c, s)
}

/// The directions of the rectangle's points: None when it holds the origin (every direction),
/// else (lo, hi) with lo in \[0, 2 pi) and hi - lo < pi.
fn angular_range(ar: [f64; 2], br: [f64; 2]) -> Option<(f64, f64)> {
    if ar[0] <= 0.0 && ar[1] >= 0.0 && br[0] <= 0.0 && br[1] >= 0.0 {
        return None;
    }
    let centre = (0.5 * (br[0] + br[1])).atan2(0.5 * (ar[0] + ar[1]));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for a in ar {
        for b in br {
            let d = (b.atan2(a) - centre + PI).rem_euclid(TAU) - PI;
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    let lo_abs = (centre + lo).rem_euclid(TAU);
    Some((lo_abs, lo_abs + (hi - lo)))
}

#[cfg(test)]
mod tests;
