//! Pattern optimisation, eqs. (1)-(14): choose the scale parameter alpha, translation d,
//! rotation theta and the assignment sigma jointly, minimising the sum of squared robot-target
//! distances (eq. 1, 4, 7) under the box (eq. 9), obstacle (eq. 10 or 12) and separation
//! (eq. 13) constraints, to the GLOBAL optimum by spatial branch-and-bound (the paper's solver,
//! its ref. \[17\]), with the assignment solved exactly (Hungarian) inside every bound.
//!
//! # Change of variables
//! Write the transform as q_j = A s_j + d with A = \[\[a, -b\], \[b, a\]\]
//! (see [`super::template`]), centre the template (s~_j = s_j - s_bar) and the starts
//! (p~_i = p_i - p_bar), and let
//! c = A s_bar + d be the pattern's centroid. Since sum_i s_sigma(i) = sum_j s_j for every
//! permutation, the objective splits exactly (the cross terms vanish because the centred sums
//! are zero):
//!
//! ```text
//! f(alpha, theta, c, sigma) = sum_i ||p_i - A s_sigma(i) - d||^2
//!                           = g(a, b, sigma) + n ||p_bar - c||^2,
//! g(a, b, sigma) = P2 + (a^2 + b^2) S2 - 2 (a D(sigma) + b X(sigma)),
//! ```
//!
//! with P2 = sum ||p~_i||^2, S2 = sum ||s~_j||^2, D(sigma) = sum_i p~_i . s~_sigma(i) and
//! X(sigma) = sum_i s~_sigma(i) x p~_i (2-D cross product). We branch over the box
//! (alpha, theta, c_1, c_2), which is (alpha, theta, d) under the bijection d = c - A s_bar; the
//! root c box is the allowed area of eq. (9) (the centroid of targets inside a convex area is
//! inside it).
//!
//! # The lower bound of a node (valid for every feasible point in it)
//! Let \[a\] x \[b\] be an outer interval box of {(a(alpha, theta), b(alpha, theta))} over the
//! node (exact interval extensions of cos and sin).
//! 1. (a^2 + b^2) >= L2 := max(min over \[a\] x \[b\] of a^2 + b^2, lambda_sep^2), since every
//!    feasible point has lambda >= lambda_sep (eq. 13 is lambda ||s_i - s_j|| >= 2r + margin,
//!    so lambda_sep = (2r + margin) / min spacing of S).
//! 2. a D(sigma) + b X(sigma) is linear in (a, b), so over the rectangle it is at most its
//!    value at one of the 4 corners; hence for every sigma it is at most
//!    M := max over corners (a_k, b_k) of max_sigma (a_k D(sigma) + b_k X(sigma)), and each
//!    inner max is one Hungarian solve with cost -(a_k p~_i . s~_j + b_k s~_j x p~_i).
//! 3. n ||p_bar - c||^2 >= n dist^2(p_bar, \[c_1\] x \[c_2\]).
//!
//! 4. A second bound on g with second-order accuracy (bounds 1-2 are only first-order, which
//!    makes the search crawl near the optimum): let sigma0 be the optimal assignment at the
//!    rectangle's centre and V column duals for it (max-form: U_i + V_j >= a0 D_ij + b0 X_ij;
//!    any V is valid below, and `Problem::interior_duals` picks slack ones).
//!    By weak duality, for every (a, b) and sigma, a D(sigma) + b X(sigma) <= sum_j V_j +
//!    sum_i max_j (l_ij(a, b) - V_j), l_ij = a p~_i.s~_j + b s~_j x p~_i, and each max_j is at
//!    most l_i,sigma0(i) - V_sigma0(i) + e_i with e_i = max_j max over the rectangle's corners of
//!    the linear (l_ij - V_j) - (l_i,sigma0(i) - V_sigma0(i)), clipped at 0. Summing, a D + b X
//!    <= a D(sigma0) + b X(sigma0) + E, E = sum e_i, so g >= P2 + min over the rectangle of the
//!    convex quadratic S2 (a^2 + b^2) - 2 (a D(sigma0) + b X(sigma0)) - 2 E (the minimum is at
//!    the projection of z = (D, X) / S2, and since the quadratic is S2 (|A - z|^2 - |z|^2) and
//!    feasible points have |A| >= lambda_sep, |A - z| >= lambda_sep - |z| bounds it too). Once
//!    sigma0 wins throughout a small rectangle, E = 0 and this is exact (bounds 1-2 are then
//!    skipped: they cannot be higher).
//!
//! 5. The alignment polygon (`OptimiserBound::Polygon`, the default; alignment.rs): the
//!    optimal sigma depends only on the direction of A = (a, b), so the max over sigma of
//!    a D + b X is the support function h(A) of the convex polygon H of all (D, X), traced by
//!    Hungarian solves at a few hundred directions for the whole search (warm-started from the
//!    neighbouring direction). Then min over the rectangle of S2 |A|^2 - 2 h(A) is exact (up
//!    to the |A| >= lambda_sep relaxation) from H's vertices whose arcs of directions meet the
//!    rectangle's, and a node makes no solve of its own; while an arc of directions is not yet
//!    traced, the apex where its two supporting lines meet stands in for it (still a valid
//!    bound). Bounds 1-2 and 4 are then not computed (`OptimiserBound::Corners` keeps them).
//!
//! So LB = max(bound 1-2, bound 4) (or bound 5) + n dist^2(p_bar, \[c\]) <= f at every feasible
//! point of the node (not clipped at 0, so that best-first order still ranks nodes whose bound
//! is negative).
//! The constraints prune too: a node is dropped when lambda_max < lambda_sep, or when the
//! interval box of some target q_j = \[a\] s~_j - \[b\] s~_j^perp + \[c\] misses the area or lies
//! wholly inside an obstacle's forbidden region; and before the bound, the c box is narrowed to
//! what eq. (9) and the obstacles leave (`Problem::narrow_centroid`). As a node shrinks,
//! \[a\] x \[b\] shrinks to a point, the corner maxima to the point's Hungarian value and the
//! c term to the exact one, so LB tends to f and the search converges.
//!
//! # Upper bound (incumbent)
//! Every node evaluates its (alpha, theta) midpoint: sigma by Hungarian (with bound 5, the
//! vertex of H optimal in A's direction; for fixed A and c the constraints do not depend on
//! sigma, so this sigma is optimal there), and two centroids, the
//! unconstrained best c = p_bar clamped to the node, and the node's centre; a candidate meeting
//! every constraint becomes the incumbent if it is better.
//!
//! # Reuse between nodes (the same numbers, fewer solves)
//! Bounds 1, 2 and 4 and the incumbent's (alpha, theta) midpoint, its g and its sigma depend
//! on the node's (alpha, theta) box only, not on its centroid box. A node split along c_1 or
//! c_2 hands them to both children (`ShapeEval`), which then skip their five to six Hungarian
//! solves and the dual computation; only the centroid narrowing, the c term and the incumbent's
//! centroid candidates are evaluated anew. Every number is the one the child would have
//! computed itself, so the search, its order and its answer are unchanged (tested bit for bit
//! against `Reuse::Off` with the corner bound; with the polygon a child's own bound could be
//! tighter when arcs were traced meanwhile, so the reused one is valid but may differ).
//!
//! # Stopping rule and certificate
//! Best-first order: the node popped has the least LB of all open nodes, so when its LB is
//! within max(gap_abs, gap_rel * UB) of the incumbent, no point anywhere is better by more than
//! that. The reported lower bound is the minimum over the open nodes and the nodes pruned by
//! bound, so `cost - lower_bound = gap` is a certificate even when the node budget runs out.

use super::alignment::{alignment_matrices, AlignmentPolygon, MatrixOracle};
use super::centroid_repair::nearest_feasible_centroid;
use super::constraints::{PatternConstraints, SLACK};
use super::hungarian::Hungarian;
use super::params::{FormationParams, OptimiserBound, TransformReading};
use super::template::{matrix, Template, Transform};
use super::FormationError;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::{PI, TAU};
use swarm::geometry::Vec2;

/// A node whose midpoint shape could still beat the incumbent tries the centroid nearest
/// p_bar that meets C1 and C2 for that shape (centroid_repair.rs), while the search has this
/// much repair work left (candidates tried x their checks, counted, so runs stay
/// deterministic). [chosen] 3e8 (at most about 0.3 s on this VM); with no incumbent yet the
/// repair runs whatever is left, so a feasible instance gets one (configs/formation.toml seed
/// 3, coordinator killed at 15: the polygon bound's search had none in 400 000 nodes).
const REPAIR_WORK: f64 = 3e8;

/// The regions `Problem::blocked_distance2` takes as certainly forbidden are shrunk by this on
/// every side, so that a centroid C2 allows with its SLACK is never inside one.
const BLOCKED_SLACK: f64 = 1e-6;

/// The optimiser's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The optimal pattern parameters (alpha*, d*, theta*), in the scenario's reading of eq. (5).
    pub transform: Transform,
    /// The targets G* = q_1..q_n.
    pub targets: Vec<Vec2>,
    /// sigma*: robot i -> target `assignment\[i\]`.
    pub assignment: Vec<usize>,
    /// The objective at the solution: sum_i ||p_i - q_sigma(i)||^2.
    pub cost: f64,
    /// A proven lower bound on the optimum over the search domain.
    pub lower_bound: f64,
    /// cost - lower_bound (>= 0): how far from optimal the solution can be.
    pub gap: f64,
    /// Whether the gap met the stopping tolerance (false: the node budget ran out first).
    pub proven: bool,
    /// Branch-and-bound nodes bounded.
    pub nodes: usize,
    /// Hungarian solves made (the alignment polygon's, or the corner bound's).
    pub solves: usize,
}

/// Solve eq. (14) over the scenario's domain (`params.optimiser`).
pub fn optimise(
    starts: &[Vec2],
    template: &Template,
    params: &FormationParams,
) -> Result<Solution, FormationError> {
    let o = &params.optimiser;
    optimise_in(starts, template, params, o.alpha_range, o.theta_range)
}

/// The no-rotation model of ref. \[10\], the paper's baseline: theta fixed at 0.
pub fn optimise_without_rotation(
    starts: &[Vec2],
    template: &Template,
    params: &FormationParams,
) -> Result<Solution, FormationError> {
    optimise_in(
        starts,
        template,
        params,
        params.optimiser.alpha_range,
        [0.0, 0.0],
    )
}

/// Solve eq. (14) with alpha in `alpha_range` and theta in `theta_range` (lo == hi fixes it;
/// section 3.4 / Table 3 restricts it to keep a letter readable).
pub fn optimise_in(
    starts: &[Vec2],
    template: &Template,
    params: &FormationParams,
    alpha_range: [f64; 2],
    theta_range: [f64; 2],
) -> Result<Solution, FormationError> {
    for (name, r) in [("alpha_range", alpha_range), ("theta_range", theta_range)] {
        if !(r[0].is_finite() && r[1].is_finite()) {
            return Err(FormationError::NonFinite(name));
        }
        if r[0] > r[1] {
            return Err(FormationError::EmptyRange {
                name,
                lo: r[0],
                hi: r[1],
            });
        }
    }
    let problem = Problem::new(starts, template, params)?;
    problem.solve(alpha_range, theta_range, params, Reuse::On)
}

/// A box of the search space: alpha, theta, and the pattern centroid c.
#[derive(Debug, Clone, Copy)]
struct Node {
    alpha: [f64; 2],
    theta: [f64; 2],
    c: [[f64; 2]; 2],
    lb: f64,
    /// Index of the node's `ShapeEval` once computed ([`NO_SHAPE`]: not yet).
    shape: u32,
}

impl Node {
    /// The squared distance from `p` to the node's centroid box.
    fn c_distance2(&self, p: Vec2) -> f64 {
        let dx = p.x - p.x.clamp(self.c[0][0], self.c[0][1]);
        let dy = p.y - p.y.clamp(self.c[1][0], self.c[1][1]);
        dx * dx + dy * dy
    }
}

/// `Node::shape` before the node's (alpha, theta) box was evaluated.
const NO_SHAPE: u32 = u32::MAX;

/// What a node computes from its (alpha, theta) box alone (module comment, "Reuse").
#[derive(Debug, Clone)]
struct ShapeEval {
    /// max(bound 1-2, bound 4): the lower bound on g over the box.
    g_lb: f64,
    /// At the (alpha, theta) midpoint: g and sigma; None when the midpoint breaks C3.
    mid: Option<(f64, Vec<usize>)>,
}

/// Whether children split along the centroid reuse their parent's [`ShapeEval`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reuse {
    On,
    /// Every node computes everything itself (the reference the reuse is tested against).
    #[cfg_attr(not(test), allow(dead_code))]
    Off,
}

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        self.lb.total_cmp(&other.lb) == Ordering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Node {
    /// Reversed, so that the max-heap pops the least lower bound (best first).
    fn cmp(&self, other: &Self) -> Ordering {
        other.lb.total_cmp(&self.lb)
    }
}

/// The best feasible point found so far.
#[derive(Debug, Clone)]
struct Incumbent {
    cost: f64,
    alpha: f64,
    theta: f64,
    c: Vec2,
    assignment: Vec<usize>,
}

/// The data of one instance, centred (see the module comment).
struct Problem {
    n: usize,
    reading: TransformReading,
    constraints: PatternConstraints,
    starts: Vec<Vec2>,
    template: Template,
    s_tilde: Vec<Vec2>,
    s_bar: Vec2,
    p_bar: Vec2,
    p2: f64,
    s2: f64,
    /// dot\[i * n + j\] = p~_i . s~_j.
    dot: Vec<f64>,
    /// cross\[i * n + j\] = s~_j x p~_i.
    cross: Vec<f64>,
    lambda_sep2: f64,
    s_max: f64,
    /// Work left for centroid repairs (candidates x regions; `REPAIR_WORK`).
    repair_work: std::cell::Cell<f64>,
}

impl Problem {
    fn new(
        starts: &[Vec2],
        template: &Template,
        params: &FormationParams,
    ) -> Result<Self, FormationError> {
        let n = starts.len();
        if template.len() != n {
            return Err(FormationError::SizeMismatch {
                template: template.len(),
                robots: n,
            });
        }
        if n == 0 {
            return Err(FormationError::SizeMismatch {
                template: 0,
                robots: 0,
            });
        }
        let s = template.vectors();
        if starts
            .iter()
            .chain(&s)
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(FormationError::NonFinite("starts or template"));
        }
        let s_bar = s.iter().sum::<Vec2>() / n as f64;
        let p_bar = starts.iter().sum::<Vec2>() / n as f64;
        let s_tilde: Vec<Vec2> = s.iter().map(|x| x - s_bar).collect();
        let p_tilde: Vec<Vec2> = starts.iter().map(|x| x - p_bar).collect();
        let (dot, cross) = alignment_matrices(&p_tilde, &s_tilde);
        let constraints = PatternConstraints::new(params);
        let spacing = template.min_spacing();
        let lambda_sep = if spacing.is_finite() {
            constraints.min_separation / spacing
        } else {
            0.0
        };
        Ok(Self {
            n,
            reading: params.transform_reading,
            constraints,
            starts: starts.to_vec(),
            template: template.clone(),
            s_max: s_tilde.iter().map(|v| v.norm()).fold(0.0, f64::max),
            p2: p_tilde.iter().map(|v| v.norm_squared()).sum(),
            s2: s_tilde.iter().map(|v| v.norm_squared()).sum(),
            s_tilde,
            s_bar,
            p_bar,
            dot,
            cross,
            lambda_sep2: lambda_sep * lambda_sep,
            repair_work: std::cell::Cell::new(REPAIR_WORK),
        })
    }

    /// max over sigma of a D(sigma) + b X(sigma), and the maximising sigma.
    fn best_alignment(&self, a: f64, b: f64, h: &mut Hungarian, sigma: &mut Vec<usize>) -> f64 {
        let n = self.n;
        -h.solve_with(
            n,
            |i, j| -(a * self.dot[i * n + j] + b * self.cross[i * n + j]),
            sigma,
        )
    }

    /// Outer interval box of (a, b) over an (alpha, theta) box.
    fn ab_box(&self, alpha: [f64; 2], theta: [f64; 2]) -> ([f64; 2], [f64; 2]) {
        let cos = cos_range(theta);
        let sin = sin_range(theta);
        match self.reading {
            TransformReading::Literal => ([alpha[0] - 1.0 + cos[0], alpha[1] - 1.0 + cos[1]], sin),
            TransformReading::Similarity => (mul(alpha, cos), mul(alpha, sin)),
        }
    }

    /// The node's lower bound, or None when no point of it can be feasible. Also narrows the
    /// node's centroid box to the part that the constraints leave (domain reduction).
    fn bound(
        &self,
        node: &mut Node,
        h: &mut Hungarian,
        sigma: &mut Vec<usize>,
        shapes: &mut Vec<ShapeEval>,
        reuse: Reuse,
        polygon: &mut Option<AlignmentPolygon>,
    ) -> Option<f64> {
        let (ar, br) = self.ab_box(node.alpha, node.theta);
        let lam2_max = sq_max(ar) + sq_max(br);
        if lam2_max < self.lambda_sep2 * (1.0 - 1e-12) - SLACK {
            return None;
        }
        if !self.narrow_centroid(node, ar, br) {
            return None;
        }
        let g_lb = match (reuse, node.shape) {
            (Reuse::On, i) if i != NO_SHAPE => shapes[i as usize].g_lb,
            _ => {
                let g_lb = match polygon {
                    Some(poly) => self.polygon_bound(ar, br, h, poly),
                    None => self.g_bound(ar, br, h, sigma),
                };
                if reuse == Reuse::On {
                    let mid = self
                        .midpoint(node, h, sigma, polygon)
                        .map(|g| (g, sigma.clone()));
                    node.shape = shapes.len() as u32;
                    shapes.push(ShapeEval { g_lb, mid });
                }
                g_lb
            }
        };
        let dc = Vec2::new(
            dist_to_interval(self.p_bar.x, node.c[0]),
            dist_to_interval(self.p_bar.y, node.c[1]),
        );
        let d2 = dc.norm_squared().max(self.blocked_distance2(node, ar, br));
        Some(g_lb + self.n as f64 * d2)
    }

    /// A lower bound on |p_bar - c|^2 over the centroids c of the node that C2 may allow: the
    /// centroid nearest p_bar in the node's box lies in no region where, for every (a, b) of
    /// the node, one target stands in one obstacle (the obstacle's square, or the square
    /// inscribed in its disc, less the spread of A s~_j over the node); when it does lie in
    /// one, the distance from p_bar to the node's box less that region. 0 when no region holds
    /// it. Without it the bound ignored C2 short of a whole target box inside an obstacle.
    /// Measured: formation.toml seed 1's first plan 17 167 -> 17 139 nodes, same optimum; the
    /// re-plan of 8 robots (seed 3, coordinator killed at 15) still ends at the node cap with
    /// gap 59.8: its least bounds sit on slivers where two targets' constraints pinch the
    /// centroid, which no single (target, obstacle) region covers.
    fn blocked_distance2(&self, node: &Node, ar: [f64; 2], br: [f64; 2]) -> f64 {
        let cons = &self.constraints;
        if cons.obstacles.is_empty() {
            return 0.0;
        }
        let half = match cons.obstacle_form {
            super::params::ObstacleConstraint::Square => cons.keep_out,
            super::params::ObstacleConstraint::Circle => cons.keep_out / std::f64::consts::SQRT_2,
        } - BLOCKED_SLACK;
        let c = node.c;
        let q = Vec2::new(
            self.p_bar.x.clamp(c[0][0], c[0][1]),
            self.p_bar.y.clamp(c[1][0], c[1][1]),
        );
        let mut best = 0.0f64;
        for s in &self.s_tilde {
            let ox = sub(scale(ar, s.x), scale(br, s.y));
            let oy = add(scale(br, s.x), scale(ar, s.y));
            for o in &cons.obstacles {
                // c + (ox, oy) lies in the square for every offset of the node.
                let rx = [o.x - half - ox[0], o.x + half - ox[1]];
                let ry = [o.y - half - oy[0], o.y + half - oy[1]];
                if !(rx[0] < q.x && q.x < rx[1] && ry[0] < q.y && q.y < ry[1]) {
                    continue;
                }
                best = best.max(distance2_outside(self.p_bar, c, rx, ry));
            }
        }
        best
    }

    /// The lower bound on g over the (a, b) rectangle: max(bound 1-2, bound 4).
    fn g_bound(
        &self,
        ar: [f64; 2],
        br: [f64; 2],
        h: &mut Hungarian,
        sigma: &mut Vec<usize>,
    ) -> f64 {
        let (b2, e) = self.dual_bound(ar, br, h, sigma);
        // With E = 0 the centre's assignment is optimal over the whole rectangle, so bound 4
        // is the exact minimum of the relaxed g there and bounds 1-2 cannot beat it.
        let b1 = if e > 0.0 {
            let lam2 = (sq_min(ar) + sq_min(br)).max(self.lambda_sep2);
            let mut m = f64::NEG_INFINITY;
            let a_corners: &[f64] = if ar[0] == ar[1] { &ar[..1] } else { &ar };
            let b_corners: &[f64] = if br[0] == br[1] { &br[..1] } else { &br };
            for &a in a_corners {
                for &b in b_corners {
                    m = m.max(self.best_alignment(a, b, h, sigma));
                }
            }
            self.p2 + lam2 * self.s2 - 2.0 * m
        } else {
            f64::NEG_INFINITY
        };
        b1.max(b2)
    }

    /// The lower bound on g over the (a, b) rectangle from the alignment polygon: exact in
    /// the assignment (alignment.rs), relaxed only in |A| >= lambda_sep.
    fn polygon_bound(
        &self,
        ar: [f64; 2],
        br: [f64; 2],
        h: &mut Hungarian,
        poly: &mut AlignmentPolygon,
    ) -> f64 {
        if self.s2 == 0.0 {
            // A one-point template: g = P2 whatever (a, b) (see `dual_bound`).
            return self.p2;
        }
        let lambda_min = (self.lambda_sep2 - SLACK).max(0.0).sqrt();
        let mut oracle = self.oracle(h);
        self.p2 + poly.quad_bound(ar, br, self.s2, lambda_min, &mut oracle)
    }

    /// The Hungarian method on this instance's alignment costs, as the polygon's oracle.
    fn oracle<'a>(&'a self, h: &'a mut Hungarian) -> MatrixOracle<'a> {
        MatrixOracle {
            n: self.n,
            dot: &self.dot,
            cross: &self.cross,
            hungarian: h,
            work: 0.0,
        }
    }

    /// g and (in `sigma`) the best assignment at the node's (alpha, theta) midpoint; None when
    /// the midpoint's scale breaks C3.
    fn midpoint(
        &self,
        node: &Node,
        h: &mut Hungarian,
        sigma: &mut Vec<usize>,
        polygon: &mut Option<AlignmentPolygon>,
    ) -> Option<f64> {
        let alpha = 0.5 * (node.alpha[0] + node.alpha[1]);
        let theta = 0.5 * (node.theta[0] + node.theta[1]);
        let (a, b) = matrix(alpha, theta, self.reading);
        if a * a + b * b < self.lambda_sep2 - SLACK {
            return None;
        }
        let alignment = match polygon {
            Some(poly) => {
                let mut oracle = self.oracle(h);
                let (z, best) = poly.assignment_at(a, b, &mut oracle);
                sigma.clear();
                sigma.extend_from_slice(best);
                a * z.x + b * z.y
            }
            None => self.best_alignment(a, b, h, sigma),
        };
        Some(self.p2 + (a * a + b * b) * self.s2 - 2.0 * alignment)
    }

    /// Constraint propagation on the centroid box: target j is q_j = o_j + c with o_j in the
    /// interval box (\[a\] x~_j - \[b\] y~_j, \[b\] x~_j + \[a\] y~_j). Eq. (9) needs
    /// c in \[area\] - o_j. For an obstacle's forbidden square (half-side R; for the exact
    /// circle, the inscribed square of half-side R / sqrt 2, which is inside the disc), when
    /// every possible q_j has its y inside the square's y-span, its x must leave the x-span:
    /// if no q_j can be left of the square, q_x >= o_x + R, so c_1 >= o_x + R - max o_j,x,
    /// and symmetrically. Removed parts hold no feasible point. False when nothing is left or a
    /// target box is wholly forbidden.
    fn narrow_centroid(&self, node: &mut Node, ar: [f64; 2], br: [f64; 2]) -> bool {
        let cons = &self.constraints;
        // The exact constraints (no SLACK): narrowing removes only points that break them, and
        // a target it leaves on a boundary then passes `feasible`'s SLACK-tolerant test even
        // after rounding (with SLACK here, a centroid narrowed onto keep_out - SLACK failed it
        // by 1e-15: a point node neither feasible nor prunable was split 400 000 times).
        let half = match cons.obstacle_form {
            super::params::ObstacleConstraint::Square => cons.keep_out,
            super::params::ObstacleConstraint::Circle => cons.keep_out / std::f64::consts::SQRT_2,
        };
        let mut c = node.c;
        for s in &self.s_tilde {
            let ox = sub(scale(ar, s.x), scale(br, s.y));
            let oy = add(scale(br, s.x), scale(ar, s.y));
            c[0][0] = c[0][0].max(cons.x_range[0] - ox[1]);
            c[0][1] = c[0][1].min(cons.x_range[1] - ox[0]);
            c[1][0] = c[1][0].max(cons.y_range[0] - oy[1]);
            c[1][1] = c[1][1].min(cons.y_range[1] - oy[0]);
            if c[0][0] > c[0][1] || c[1][0] > c[1][1] {
                return false;
            }
            for o in &cons.obstacles {
                let x = add(ox, c[0]);
                let y = add(oy, c[1]);
                if cons.box_inside_an_obstacle(x, y) {
                    return false;
                }
                let y_inside = y[0] > o.y - half && y[1] < o.y + half;
                let x_inside = x[0] > o.x - half && x[1] < o.x + half;
                if y_inside && x[0] > o.x - half {
                    c[0][0] = c[0][0].max(o.x + half - ox[1]);
                }
                if y_inside && x[1] < o.x + half {
                    c[0][1] = c[0][1].min(o.x - half - ox[0]);
                }
                if x_inside && y[0] > o.y - half {
                    c[1][0] = c[1][0].max(o.y + half - oy[1]);
                }
                if x_inside && y[1] < o.y + half {
                    c[1][1] = c[1][1].min(o.y - half - oy[0]);
                }
                if c[0][0] > c[0][1] || c[1][0] > c[1][1] {
                    return false;
                }
            }
        }
        node.c = c;
        true
    }

    /// The second bound on min g over the rectangle (module comment, bound 4): duals V of the
    /// assignment at the rectangle's centre give, for every (a, b) in it and every sigma',
    /// a D(sigma') + b X(sigma') <= a D(sigma) + b X(sigma) + E, sigma the centre's optimum;
    /// then g >= P2 + min over the rectangle of \[S2 (a^2 + b^2) - 2 (a D + b X)\] - 2 E.
    fn dual_bound(
        &self,
        ar: [f64; 2],
        br: [f64; 2],
        h: &mut Hungarian,
        sigma: &mut Vec<usize>,
    ) -> (f64, f64) {
        let n = self.n;
        if self.s2 == 0.0 {
            // A template of one point (every point at its centroid): the shape is a point,
            // g = P2 whatever (a, b). Without this, z = (D, X) / S2 = 0 / 0 made the bound NaN,
            // and one robot spent the whole node budget and reported an infinite gap.
            return (self.p2, 0.0);
        }
        let (a0, b0) = (0.5 * (ar[0] + ar[1]), 0.5 * (br[0] + br[1]));
        self.best_alignment(a0, b0, h, sigma);
        let duals = self.interior_duals(a0, b0, sigma);
        let big_v = |j: usize| duals[j];
        let (mut d, mut x, mut e) = (0.0, 0.0, 0.0);
        for (i, &k) in sigma.iter().enumerate() {
            let (dk, xk, vk) = (self.dot[i * n + k], self.cross[i * n + k], big_v(k));
            d += dk;
            x += xk;
            let mut worst: f64 = 0.0;
            for j in 0..n {
                if j == k {
                    continue;
                }
                let (dd, dx, dv) = (
                    self.dot[i * n + j] - dk,
                    self.cross[i * n + j] - xk,
                    big_v(j) - vk,
                );
                // A linear function of (a, b): its maximum over the rectangle is at a corner.
                let at = |a: f64, b: f64| a * dd + b * dx - dv;
                worst = worst.max(at(ar[0], br[0])).max(at(ar[0], br[1]));
                worst = worst.max(at(ar[1], br[0])).max(at(ar[1], br[1]));
            }
            e += worst;
        }
        // S2 |(a, b)|^2 - 2 (a D + b X) is least at the projection of (D, X) / S2.
        let pa = (d / self.s2).clamp(ar[0], ar[1]);
        let pb = (x / self.s2).clamp(br[0], br[1]);
        // S2 |A|^2 - 2 A.(D, X) = S2 (|A - z|^2 - |z|^2), z = (D, X) / S2, and a feasible A
        // has |A| >= lambda_sep, so |A - z| >= lambda_sep - |z| as well.
        let z = Vec2::new(d / self.s2, x / self.s2);
        let to_rect = (pa - z.x).powi(2) + (pb - z.y).powi(2);
        let to_sep = (self.lambda_sep2.sqrt() - z.norm()).max(0.0).powi(2);
        let quad = self.s2 * (to_rect.max(to_sep) - z.norm_squared());
        (self.p2 + quad - 2.0 * e, e)
    }

    /// Column duals V for the max-assignment `sigma` at (a0, b0) that leave the non-assignment
    /// edges as slack as they can be: the Hungarian's own potentials make about 2n edges tight,
    /// which would keep E > 0 in every rectangle around them (a first-order bound). Dual
    /// feasibility for a fixed sigma is the difference system V_j - V_sigma(i) >= w_ij -
    /// w_i,sigma(i) (w = a0 D_ij + b0 X_ij); its least solution (longest paths from a virtual
    /// source, Bellman-Ford) and its greatest (the same on the reversed arcs, negated) are both
    /// feasible, and their mean is slack on every arc that either leaves slack. Any V keeps
    /// bound 4 valid (weak duality), so rounding here can only loosen it.
    fn interior_duals(&self, a0: f64, b0: f64, sigma: &[usize]) -> Vec<f64> {
        let n = self.n;
        let w = |i: usize, j: usize| a0 * self.dot[i * n + j] + b0 * self.cross[i * n + j];
        let mut lo = vec![0.0; n];
        let mut hi = vec![0.0; n];
        for _ in 0..n {
            let mut changed = false;
            for (i, &k) in sigma.iter().enumerate() {
                let wk = w(i, k);
                for j in 0..n {
                    if j == k {
                        continue;
                    }
                    let c = w(i, j) - wk;
                    if lo[k] + c > lo[j] {
                        lo[j] = lo[k] + c;
                        changed = true;
                    }
                    // Reversed: W = -V with W_k - W_j >= c.
                    if hi[j] + c > hi[k] {
                        hi[k] = hi[j] + c;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        lo.iter().zip(&hi).map(|(l, h)| 0.5 * (l - h)).collect()
    }

    /// Whether the pattern with matrix (a, b) and centroid c meets C1-C3.
    fn feasible(&self, a: f64, b: f64, c: Vec2) -> bool {
        if a * a + b * b < self.lambda_sep2 - SLACK {
            return false;
        }
        self.s_tilde.iter().all(|s| {
            let q = Vec2::new(a * s.x - b * s.y, b * s.x + a * s.y) + c;
            self.constraints.in_box(q) && self.constraints.clear_of_obstacles(q)
        })
    }

    /// Try the node's midpoint as a new incumbent.
    fn try_incumbent(
        &self,
        node: &Node,
        h: &mut Hungarian,
        sigma: &mut Vec<usize>,
        best: &mut Option<Incumbent>,
        shapes: &[ShapeEval],
        polygon: &mut Option<AlignmentPolygon>,
    ) {
        let alpha = 0.5 * (node.alpha[0] + node.alpha[1]);
        let theta = 0.5 * (node.theta[0] + node.theta[1]);
        let (a, b) = matrix(alpha, theta, self.reading);
        let (g, sigma): (f64, &[usize]) = if node.shape != NO_SHAPE {
            match &shapes[node.shape as usize].mid {
                Some((g, s)) => (*g, s),
                None => return,
            }
        } else {
            match self.midpoint(node, h, sigma, polygon) {
                Some(g) => (g, sigma),
                None => return,
            }
        };
        let clamp = |v: f64, r: [f64; 2]| v.clamp(r[0], r[1]);
        let candidates = [
            Vec2::new(
                clamp(self.p_bar.x, node.c[0]),
                clamp(self.p_bar.y, node.c[1]),
            ),
            Vec2::new(
                0.5 * (node.c[0][0] + node.c[0][1]),
                0.5 * (node.c[1][0] + node.c[1][1]),
            ),
        ];
        for c in candidates {
            let f = g + self.n as f64 * (self.p_bar - c).norm_squared();
            if best.as_ref().is_some_and(|b| b.cost <= f) || !self.feasible(a, b, c) {
                continue;
            }
            *best = Some(Incumbent {
                cost: f,
                alpha,
                theta,
                c,
                assignment: sigma.to_vec(),
            });
        }
        // The centroid nearest p_bar that meets C1 and C2 for this shape (centroid_repair.rs),
        // when it could beat the incumbent and repair work is left (`REPAIR_WORK`; always
        // while there is no incumbent).
        let ub = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
        let left = self.repair_work.get();
        if g + self.n as f64 * node.c_distance2(self.p_bar) < ub && (best.is_none() || left > 0.0) {
            let offsets: Vec<Vec2> = self
                .s_tilde
                .iter()
                .map(|s| Vec2::new(a * s.x - b * s.y, b * s.x + a * s.y))
                .collect();
            let mut work = 0.0;
            let found = nearest_feasible_centroid(
                &offsets,
                &self.constraints,
                self.p_bar,
                node.c,
                &mut work,
            );
            self.repair_work.set(left - work);
            if let Some(c) = found {
                let f = g + self.n as f64 * (self.p_bar - c).norm_squared();
                if f < ub && self.feasible(a, b, c) {
                    *best = Some(Incumbent {
                        cost: f,
                        alpha,
                        theta,
                        c,
                        assignment: sigma.to_vec(),
                    });
                }
            }
        }
    }

    /// How far each of the node's four dimensions moves the targets.
    fn widths(&self, node: &Node) -> [f64; 4] {
        [
            (node.alpha[1] - node.alpha[0]) * self.s_max,
            (node.theta[1] - node.theta[0]) * self.s_max * node.alpha[1].abs().max(1.0),
            node.c[0][1] - node.c[0][0],
            node.c[1][1] - node.c[1][0],
        ]
    }

    /// Whether the node is too small to split further (every width at rounding level).
    fn degenerate(&self, node: &Node) -> bool {
        let scale = 1.0 + self.s_max + self.p_bar.norm();
        self.widths(node).iter().all(|w| *w <= 1e-12 * scale)
    }

    /// Split a node in two along its widest dimension, measured by how far it moves targets.
    fn split(&self, node: &Node) -> [Node; 2] {
        let widths = self.widths(node);
        let mut k = 0;
        for i in 1..4 {
            if widths[i] > widths[k] {
                k = i;
            }
        }
        let (mut lo, mut hi) = (*node, *node);
        if k < 2 {
            // A new (alpha, theta) box: its shape is evaluated afresh.
            lo.shape = NO_SHAPE;
            hi.shape = NO_SHAPE;
        }
        let halve = |r: [f64; 2]| 0.5 * (r[0] + r[1]);
        match k {
            0 => {
                let m = halve(node.alpha);
                lo.alpha[1] = m;
                hi.alpha[0] = m;
            }
            1 => {
                let m = halve(node.theta);
                lo.theta[1] = m;
                hi.theta[0] = m;
            }
            axis => {
                let m = halve(node.c[axis - 2]);
                lo.c[axis - 2][1] = m;
                hi.c[axis - 2][0] = m;
            }
        }
        [lo, hi]
    }

    fn solve(
        &self,
        alpha: [f64; 2],
        theta: [f64; 2],
        params: &FormationParams,
        reuse: Reuse,
    ) -> Result<Solution, FormationError> {
        let opts = &params.optimiser;
        let mut shapes = Vec::new();
        let mut h = Hungarian::new();
        let mut sigma = Vec::with_capacity(self.n);
        let mut best: Option<Incumbent> = None;
        let cons = &self.constraints;
        let mut root = Node {
            alpha,
            theta,
            c: [cons.x_range, cons.y_range],
            lb: 0.0,
            shape: NO_SHAPE,
        };
        let mut polygon = match opts.bound {
            OptimiserBound::Polygon => {
                let scale = (self.p2 * self.s2).sqrt();
                let mut oracle = self.oracle(&mut h);
                let most = (opts.max_solves, opts.max_work);
                Some(AlignmentPolygon::new(
                    &mut oracle,
                    scale,
                    most,
                    opts.warm_start,
                ))
            }
            OptimiserBound::Corners => None,
        };
        let mut heap = BinaryHeap::new();
        let mut nodes = 1;
        // The least lower bound among nodes discarded by bound (not by infeasibility).
        let mut pruned_lb = f64::INFINITY;
        let poly = &mut polygon;
        if let Some(lb) = self.bound(&mut root, &mut h, &mut sigma, &mut shapes, reuse, poly) {
            root.lb = lb;
            self.try_incumbent(&root, &mut h, &mut sigma, &mut best, &shapes, poly);
            heap.push(root);
        }
        // Without an incumbent (ub infinite) nothing is pruned by bound.
        let tolerance = |ub: f64| {
            if ub.is_finite() {
                opts.gap_abs.max(opts.gap_rel * ub)
            } else {
                0.0
            }
        };
        let mut proven = true;
        while let Some(node) = heap.pop() {
            let ub = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
            if node.lb >= ub - tolerance(ub) {
                pruned_lb = pruned_lb.min(node.lb);
                break;
            }
            if nodes >= opts.max_nodes {
                proven = false;
                heap.push(node);
                break;
            }
            if self.degenerate(&node) {
                // Nothing left to split (a box at rounding size that the midpoint test still
                // rejects): its bound stays in the reported lower bound, so the gap says so.
                pruned_lb = pruned_lb.min(node.lb);
                continue;
            }
            for mut child in self.split(&node) {
                nodes += 1;
                let Some(lb) = self.bound(&mut child, &mut h, &mut sigma, &mut shapes, reuse, poly)
                else {
                    continue;
                };
                child.lb = lb.max(node.lb);
                self.try_incumbent(&child, &mut h, &mut sigma, &mut best, &shapes, poly);
                let ub = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
                if child.lb < ub - tolerance(ub) {
                    heap.push(child);
                } else {
                    pruned_lb = pruned_lb.min(child.lb);
                }
            }
        }
        let best = best.ok_or(FormationError::Infeasible)?;
        let open_lb = heap.peek().map_or(f64::INFINITY, |n| n.lb);
        let lower_bound = open_lb.min(pruned_lb).min(best.cost);
        let (a, b) = matrix(best.alpha, best.theta, self.reading);
        let a_s_bar = Vec2::new(
            a * self.s_bar.x - b * self.s_bar.y,
            b * self.s_bar.x + a * self.s_bar.y,
        );
        let d = best.c - a_s_bar;
        let transform = Transform {
            alpha: best.alpha,
            d: [d.x, d.y],
            theta: best.theta,
        };
        let targets = transform.targets(self.reading, &self.template);
        let cost = (0..self.n)
            .map(|i| (self.starts[i] - targets[best.assignment[i]]).norm_squared())
            .sum::<f64>();
        let proven = proven && cost - lower_bound <= tolerance(cost) + 1e-9;
        Ok(Solution {
            transform,
            targets,
            assignment: best.assignment,
            cost,
            lower_bound,
            gap: (cost - lower_bound).max(0.0),
            proven,
            nodes,
            solves: match polygon {
                Some(p) => p.solves(),
                None => h.solves(),
            },
        })
    }
}

fn mul(x: [f64; 2], y: [f64; 2]) -> [f64; 2] {
    let p = [x[0] * y[0], x[0] * y[1], x[1] * y[0], x[1] * y[1]];
    [
        p.iter().copied().fold(f64::INFINITY, f64::min),
        p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    ]
}

fn scale(x: [f64; 2], k: f64) -> [f64; 2] {
    if k >= 0.0 {
        [x[0] * k, x[1] * k]
    } else {
        [x[1] * k, x[0] * k]
    }
}

fn add(x: [f64; 2], y: [f64; 2]) -> [f64; 2] {
    [x[0] + y[0], x[1] + y[1]]
}

fn sub(x: [f64; 2], y: [f64; 2]) -> [f64; 2] {
    [x[0] - y[1], x[1] - y[0]]
}

/// min of v^2 over v in the interval.
fn sq_min(x: [f64; 2]) -> f64 {
    if x[0] > 0.0 {
        x[0] * x[0]
    } else if x[1] < 0.0 {
        x[1] * x[1]
    } else {
        0.0
    }
}

/// max of v^2 over v in the interval.
fn sq_max(x: [f64; 2]) -> f64 {
    (x[0] * x[0]).max(x[1] * x[1])
}

/// The squared distance from `p` to the box `c` less the open rectangle `rx` x `ry` (infinite
/// when the rectangle covers the box: no centroid is left).
fn distance2_outside(p: Vec2, c: [[f64; 2]; 2], rx: [f64; 2], ry: [f64; 2]) -> f64 {
    let to_box = |x: [f64; 2], y: [f64; 2]| {
        if x[0] > x[1] || y[0] > y[1] {
            return f64::INFINITY;
        }
        let dx = dist_to_interval(p.x, x);
        let dy = dist_to_interval(p.y, y);
        dx * dx + dy * dy
    };
    // The parts of the box left, right, below and above the rectangle.
    let parts = [
        ([c[0][0], c[0][1].min(rx[0])], c[1]),
        ([c[0][0].max(rx[1]), c[0][1]], c[1]),
        (c[0], [c[1][0], c[1][1].min(ry[0])]),
        (c[0], [c[1][0].max(ry[1]), c[1][1]]),
    ];
    parts
        .iter()
        .map(|(x, y)| to_box(*x, *y))
        .fold(f64::INFINITY, f64::min)
}

fn dist_to_interval(v: f64, r: [f64; 2]) -> f64 {
    if v < r[0] {
        r[0] - v
    } else if v > r[1] {
        v - r[1]
    } else {
        0.0
    }
}

/// The exact range of cos over \[lo, hi\].
fn cos_range(t: [f64; 2]) -> [f64; 2] {
    let (c0, c1) = (t[0].cos(), t[1].cos());
    let mut lo = c0.min(c1);
    let mut hi = c0.max(c1);
    // A maximum at 2 pi k, a minimum at pi + 2 pi k inside the interval.
    if (t[0] / TAU).ceil() * TAU <= t[1] {
        hi = 1.0;
    }
    if ((t[0] - PI) / TAU).ceil() * TAU + PI <= t[1] {
        lo = -1.0;
    }
    [lo, hi]
}

/// The exact range of sin over \[lo, hi\] (sin t = cos(t - pi/2)).
fn sin_range(t: [f64; 2]) -> [f64; 2] {
    let shifted = cos_range([t[0] - PI / 2.0, t[1] - PI / 2.0]);
    // Rounding of the shift must not lose the endpoint values themselves.
    let (s0, s1) = (t[0].sin(), t[1].sin());
    [shifted[0].min(s0.min(s1)), shifted[1].max(s0.max(s1))]
}

#[cfg(test)]
mod tests;
