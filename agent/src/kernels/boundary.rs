//! Boundary-point extraction (paper §3.4, Fig. 4; spec §2.8 and §5 item 20).
//!
//! The sensed obstacle points are projected onto a circle around the robot:
//! their angles ⟨B_s − X_i⟩ are sorted circularly and split into arcs wherever
//! the angular gap between neighbours is too wide to be sampling resolution.
//! Each arc yields two boundary points P_j: the actual obstacle points at its
//! clockwise and counter-clockwise angular ends. N_P = 2 is a *continuous*
//! view, N_P > 2 a *discontinuous* one, N_P = 0 means fully surrounded.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use swarm::geometry::{angle_of, Vec2};

/// Tunables of the boundary scan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Largest spacing between consecutive sampled obstacle boundary points
    /// (2.0). [chosen] spec §5 items 1 and 20.
    pub sample_spacing: f64,
    /// Safety factor on the angle 2·asin(s / 2d) that two neighbouring samples
    /// (spacing s) at distance d can subtend; a wider angular gap is free
    /// space (2.0). [chosen] spec §5 item 20 ("2–3× spacing/distance").
    pub gap_factor: f64,
    /// Smallest angular gap (rad) ever treated as free space (0.05 rad ≈ 2.9°,
    /// a 5-unit opening at distance 100). [chosen] spec §5 item 20.
    pub min_gap_angle: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            sample_spacing: 2.0,
            gap_factor: 2.0,
            min_gap_angle: 0.05,
        }
    }
}

/// One projected arc (a run of angularly contiguous obstacle points).
#[derive(Clone, Debug, PartialEq)]
pub struct Arc {
    /// Obstacle point at the clockwise (smaller-angle) end.
    pub cw_end: Vec2,
    /// Obstacle point at the counter-clockwise end.
    pub ccw_end: Vec2,
    /// ⟨cw_end − X_i⟩ in (-π, π].
    pub cw_angle: f64,
    /// ⟨ccw_end − X_i⟩ in (-π, π].
    pub ccw_angle: f64,
    /// Number of obstacle points in the arc.
    pub n_points: usize,
}

/// Result of a boundary scan, arcs listed counter-clockwise.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Scan {
    /// Arcs in counter-clockwise order, each followed by a free gap.
    pub arcs: Vec<Arc>,
    /// True when obstacle points were seen all around with no free gap
    /// (N_P = 0; BSOA then falls back to case 1, spec §5 item 20).
    pub surrounded: bool,
    /// Number of obstacle points inside the scan radius.
    pub n_in_range: usize,
}

impl Scan {
    /// N_P, the number of boundary points (2 per arc).
    pub fn n_p(&self) -> usize {
        2 * self.arcs.len()
    }

    /// A continuous view (N_P = 2, Fig. 4(a)).
    pub fn is_continuous(&self) -> bool {
        self.arcs.len() == 1
    }

    /// A discontinuous view (N_P > 2, Fig. 4(b)).
    pub fn is_discontinuous(&self) -> bool {
        self.arcs.len() > 1
    }

    /// Boundary points P_1..P_NP in counter-clockwise order:
    /// arc0.cw_end, arc0.ccw_end, arc1.cw_end, ...
    pub fn boundary_points(&self) -> Vec<Vec2> {
        self.arcs
            .iter()
            .flat_map(|a| [a.cw_end, a.ccw_end])
            .collect()
    }

    /// Angle ⟨P_j − X_i⟩ of boundary point `j` (indexing as
    /// [`Scan::boundary_points`]).
    pub fn boundary_angle(&self, j: usize) -> f64 {
        let a = &self.arcs[j / 2];
        if j.is_multiple_of(2) {
            a.cw_angle
        } else {
            a.ccw_angle
        }
    }

    /// j2 for a given j1 (eq. 20): the boundary point on the far side of the
    /// free gap that touches P_j1 (pairs ②③, ④⑤, ⑥① of Fig. 4(b)).
    pub fn gap_partner(&self, j: usize) -> usize {
        let n = self.n_p();
        if j.is_multiple_of(2) {
            (j + n - 1) % n
        } else {
            (j + 1) % n
        }
    }

    /// Angular width (rad, in (0, 2π)) of the free gap between boundary
    /// point `j` and its [`Scan::gap_partner`].
    pub fn gap_width(&self, j: usize) -> f64 {
        let k = self.gap_partner(j);
        let (from, to) = if !j.is_multiple_of(2) { (j, k) } else { (k, j) };
        let w = (self.boundary_angle(to) - self.boundary_angle(from)).rem_euclid(TAU);
        if w == 0.0 {
            TAU
        } else {
            w
        }
    }
}

/// Largest angle two neighbouring boundary samples at distance `d` can
/// subtend, times the safety factor, floored by `min_gap_angle`.
fn gap_threshold(d: f64, p: &Params) -> f64 {
    let s = p.sample_spacing;
    let sub = if d <= s / 2.0 {
        PI
    } else {
        2.0 * (s / (2.0 * d)).asin()
    };
    (p.gap_factor * sub).max(p.min_gap_angle)
}

/// Most angular bins a scan uses; a finer bin width (a tiny `min_gap_angle` and
/// `gap_factor`) falls back to sorting the points.
const MAX_BINS: usize = 4096;

/// Scans the obstacle points around `x` (paper §3.4; spec §5 item 20).
/// Only points with 0 < ‖B_s − X_i‖ < `range` count; BSOA passes
/// min(L_B, L_T) (Table 2, line 1).
///
/// The points are taken in angular order (ties: nearer first). A gap is free only if it is
/// wider than `gap_threshold` at the range, so the points are dropped into angular bins
/// half that wide: no gap inside a bin can be free, and only each bin's first and last
/// point (in that order) matter, which is the same scan as sorting them all, in linear
/// time (test `binned_scan_is_the_sorted_scan`).
pub fn scan(x: &Vec2, obstacle_points: &[Vec2], range: f64, p: &Params) -> Scan {
    scan_with(x, obstacle_points, range, p, bin_width(range, p))
}

/// The bin width [`scan`] uses for `range`, if binning applies.
fn bin_width(range: f64, p: &Params) -> Option<f64> {
    let width = gap_threshold(range, p) * 0.5;
    let bins = TAU / width;
    (bins.is_finite() && bins >= 1.0 && bins <= MAX_BINS as f64).then_some(width)
}

/// [`scan`] of points already known to lie in range: `dists[i]` = ‖points[i] − x‖, with
/// 0 < dists[i] < `range` (BSOA has measured them). The same scan, without measuring again.
pub fn scan_measured(x: &Vec2, points: &[Vec2], dists: &[f64], range: f64, p: &Params) -> Scan {
    debug_assert_eq!(points.len(), dists.len());
    let pts: Vec<(f64, f64, Vec2)> = points
        .iter()
        .zip(dists)
        .map(|(b, &d)| (angle_of(&(b - x)), d, *b))
        .collect();
    scan_points(pts, p, bin_width(range, p))
}

/// [`scan`] by angular bins of `width` (Some) or by sorting every point (None).
fn scan_with(
    x: &Vec2,
    obstacle_points: &[Vec2],
    range: f64,
    p: &Params,
    width: Option<f64>,
) -> Scan {
    // (angle, distance, point); points on the robot itself are ignored.
    let mut pts: Vec<(f64, f64, Vec2)> = Vec::with_capacity(obstacle_points.len());
    pts.extend(obstacle_points.iter().filter_map(|b| {
        let r = b - x;
        let d = r.norm();
        (d < range && d > 1e-9).then(|| (angle_of(&r), d, *b))
    }));
    scan_points(pts, p, width)
}

/// The scan of (angle, distance, point) triples.
fn scan_points(mut pts: Vec<(f64, f64, Vec2)>, p: &Params, width: Option<f64>) -> Scan {
    let n = pts.len();
    if n == 0 {
        return Scan::default();
    }
    let order =
        |a: &(f64, f64, Vec2), b: &(f64, f64, Vec2)| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1));
    // Runs of angularly consecutive points no free gap can split, in angular order:
    // (first point, last point, number of points).
    let runs: Vec<(usize, usize, usize)> = match width {
        None => {
            pts.sort_by(order);
            (0..n).map(|i| (i, i, 1)).collect()
        }
        Some(w) => {
            let nb = (TAU / w).ceil() as usize;
            // Bin of an angle in [-π, π]: monotone in the angle, so bins follow the order.
            let bin = |a: f64| (((a + PI) / w) as usize).min(nb - 1);
            let mut by_bin = vec![(usize::MAX, usize::MAX, 0usize); nb];
            for (i, q) in pts.iter().enumerate() {
                let b = &mut by_bin[bin(q.0)];
                if b.2 == 0 {
                    *b = (i, i, 1);
                } else {
                    // First and last in the order; ties as a stable sort leaves them.
                    if order(q, &pts[b.0]).is_lt() {
                        b.0 = i;
                    }
                    if order(q, &pts[b.1]).is_ge() {
                        b.1 = i;
                    }
                    b.2 += 1;
                }
            }
            by_bin.into_iter().filter(|b| b.2 > 0).collect()
        }
    };
    let m = runs.len();

    // gap_of(j): the angular gap after run j, to the next run (circularly).
    let gap_of = |j: usize| {
        let (a, b) = (&pts[runs[j].1], &pts[runs[(j + 1) % m].0]);
        if j + 1 == m {
            b.0 - a.0 + TAU
        } else {
            b.0 - a.0
        }
    };
    // is_free[j]: the gap after run j is free space.
    let is_free: Vec<bool> = (0..m)
        .map(|j| {
            let (a, b) = (&pts[runs[j].1], &pts[runs[(j + 1) % m].0]);
            let gap = gap_of(j);
            // The threshold is never below min_gap_angle: most gaps (neighbouring samples)
            // are decided without its asin.
            (gap > p.min_gap_angle || p.min_gap_angle.is_nan())
                && gap > gap_threshold(a.1.min(b.1), p)
        })
        .collect();
    // Canonical start: after the widest free gap (ties: first), so a frontal
    // view lists its arcs from right to left.
    let widest = (0..m)
        .filter(|&j| is_free[j])
        .fold(None, |best: Option<usize>, j| match best {
            Some(b) if gap_of(b) >= gap_of(j) => Some(b),
            _ => Some(j),
        });
    let Some(first_gap) = widest else {
        return Scan {
            arcs: Vec::new(),
            surrounded: true,
            n_in_range: n,
        };
    };

    let mut arcs = Vec::new();
    let start = (first_gap + 1) % m;
    let mut arc_start = runs[start].0;
    let mut count = 0;
    for step in 0..m {
        let j = (start + step) % m;
        count += runs[j].2;
        if is_free[j] {
            let (c, w) = (&pts[arc_start], &pts[runs[j].1]);
            arcs.push(Arc {
                cw_end: c.2,
                ccw_end: w.2,
                cw_angle: c.0,
                ccw_angle: w.0,
                n_points: count,
            });
            arc_start = runs[(j + 1) % m].0;
            count = 0;
        }
    }
    Scan {
        arcs,
        surrounded: false,
        n_in_range: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarm::geometry::sample_boundary;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Vec2> {
        sample_boundary(
            &[
                Vec2::new(x0, y0),
                Vec2::new(x1, y0),
                Vec2::new(x1, y1),
                Vec2::new(x0, y1),
            ],
            2.0,
        )
    }

    fn close(a: &Vec2, b: &Vec2) -> bool {
        (a - b).norm() < 1e-9
    }

    #[test]
    fn empty_view() {
        let s = scan(
            &Vec2::new(0.0, 0.0),
            &rect(200.0, 0.0, 210.0, 10.0),
            100.0,
            &Params::default(),
        );
        assert_eq!(s.n_p(), 0);
        assert!(!s.surrounded && !s.is_continuous() && !s.is_discontinuous());
    }

    #[test]
    fn continuous_view_of_one_wall() {
        // A horizontal wall from x=-30 to 30 at y=40, robot at origin.
        let wall = rect(-30.0, 40.0, 30.0, 44.0);
        let s = scan(&Vec2::new(0.0, 0.0), &wall, 100.0, &Params::default());
        assert!(s.is_continuous(), "arcs: {:?}", s.arcs);
        assert_eq!(s.n_p(), 2);
        let bp = s.boundary_points();
        // Angular extremes are the near corners (30,40) then (-30,40) CCW.
        assert!(close(&bp[0], &Vec2::new(30.0, 40.0)), "{:?}", bp[0]);
        assert!(close(&bp[1], &Vec2::new(-30.0, 40.0)), "{:?}", bp[1]);
        assert_eq!(s.gap_partner(0), 1);
        assert_eq!(s.gap_partner(1), 0);
        assert!(s.gap_width(1) > PI);
    }

    #[test]
    fn discontinuous_view_of_three_blocks() {
        // Three blocks in front with two free gaps (Fig. 4(b)).
        let mut pts = rect(-50.0, 40.0, -20.0, 45.0);
        pts.extend(rect(-5.0, 40.0, 5.0, 45.0));
        pts.extend(rect(20.0, 40.0, 50.0, 45.0));
        let s = scan(&Vec2::new(0.0, 0.0), &pts, 100.0, &Params::default());
        assert!(s.is_discontinuous());
        assert_eq!(s.n_p(), 6);
        let bp = s.boundary_points();
        let want = [
            Vec2::new(50.0, 40.0),
            Vec2::new(20.0, 45.0),
            Vec2::new(5.0, 40.0),
            Vec2::new(-5.0, 40.0),
            Vec2::new(-20.0, 45.0),
            Vec2::new(-50.0, 40.0),
        ];
        for (g, w) in bp.iter().zip(want.iter()) {
            assert!(close(g, w), "got {g:?}, want {w:?}");
        }
        // gap pairs ②③, ④⑤, ⑥① (0-based: 1-2, 3-4, 5-0)
        assert_eq!(s.gap_partner(1), 2);
        assert_eq!(s.gap_partner(2), 1);
        assert_eq!(s.gap_partner(3), 4);
        assert_eq!(s.gap_partner(5), 0);
        assert_eq!(s.gap_partner(0), 5);
        assert!(s.gap_width(1) < 0.5 && s.gap_width(5) > PI);
    }

    #[test]
    fn occlusion_overlap_stays_continuous() {
        // A near block and a farther block overlapping in angle project onto
        // one continuous arc.
        let mut pts = rect(-20.0, 30.0, 5.0, 32.0);
        pts.extend(rect(0.0, 60.0, 30.0, 62.0));
        let s = scan(&Vec2::new(0.0, 0.0), &pts, 100.0, &Params::default());
        assert!(s.is_continuous(), "{:?}", s.arcs.len());
    }

    #[test]
    fn arc_across_the_pi_seam_is_not_split() {
        // Wall to the west (angles around ±π).
        let wall = rect(-40.0, -20.0, -36.0, 20.0);
        let s = scan(&Vec2::new(0.0, 0.0), &wall, 100.0, &Params::default());
        assert!(s.is_continuous());
        assert!(close(&s.arcs[0].cw_end, &Vec2::new(-36.0, 20.0)));
        assert!(close(&s.arcs[0].ccw_end, &Vec2::new(-36.0, -20.0)));
    }

    #[test]
    fn wall_leaving_range_ends_on_the_sensing_circle() {
        // A long wall: its arc ends where the wall leaves the 100 circle.
        let wall = rect(-300.0, 50.0, 300.0, 52.0);
        let s = scan(&Vec2::new(0.0, 0.0), &wall, 100.0, &Params::default());
        assert!(s.is_continuous());
        for p in s.boundary_points() {
            let d = p.norm();
            assert!(d < 100.0 && d > 97.0, "end point at distance {d}");
        }
    }

    #[test]
    fn surrounded_and_far_points() {
        let ring = rect(-20.0, -20.0, 20.0, 20.0);
        let s = scan(&Vec2::new(0.0, 0.0), &ring, 100.0, &Params::default());
        assert!(s.surrounded);
        assert_eq!(s.n_p(), 0);
        assert_eq!(s.n_in_range, ring.len());
    }

    #[test]
    fn narrow_but_real_gap_is_found_close_up() {
        // Two walls 8 units apart, 20 units ahead: a real opening.
        let mut pts = rect(-40.0, 20.0, -4.0, 22.0);
        pts.extend(rect(4.0, 20.0, 40.0, 22.0));
        let s = scan(&Vec2::new(0.0, 0.0), &pts, 100.0, &Params::default());
        assert_eq!(s.n_p(), 4);
        // The same walls touching (gap closed to 1 sample spacing) are one arc.
        let mut pts = rect(-40.0, 20.0, -1.0, 22.0);
        pts.extend(rect(1.0, 20.0, 40.0, 22.0));
        assert!(scan(&Vec2::new(0.0, 0.0), &pts, 100.0, &Params::default()).is_continuous());
    }

    #[test]
    fn binned_scan_is_the_sorted_scan() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let p = Params::default();
        let mut shapes: Vec<Vec<Vec2>> = Vec::new();
        for _ in 0..300 {
            // A few boxes and random clutter (with duplicates) around the robot.
            let mut pts = Vec::new();
            for _ in 0..rng.gen_range(1..4) {
                let (x0, y0) = (rng.gen_range(-120.0..100.0), rng.gen_range(-120.0..100.0));
                let (w, h) = (rng.gen_range(1.0..60.0), rng.gen_range(1.0..60.0));
                pts.extend(rect(x0, y0, x0 + w, y0 + h));
            }
            for _ in 0..rng.gen_range(0..30) {
                let q = Vec2::new(rng.gen_range(-100.0..100.0), rng.gen_range(-100.0..100.0));
                pts.push(q);
                if rng.gen_bool(0.2) {
                    pts.push(q);
                }
            }
            shapes.push(pts);
        }
        // Points exactly behind one another and on the ±π seam.
        shapes.push(vec![
            Vec2::new(-10.0, 0.0),
            Vec2::new(-20.0, 0.0),
            Vec2::new(-30.0, -0.0),
            Vec2::new(5.0, 5.0),
        ]);
        shapes.push(rect(-50.0, -1.0, -40.0, 1.0));
        let (mut kinds, mut binned_ran) = (std::collections::BTreeSet::new(), 0);
        for pts in &shapes {
            for x in [Vec2::new(0.0, 0.0), Vec2::new(0.3, -0.7)] {
                let a = scan(&x, pts, 100.0, &p);
                let b = scan_with(&x, pts, 100.0, &p, None);
                assert_eq!(a, b, "x {x:?} points {pts:?}");
                let (near, dists): (Vec<Vec2>, Vec<f64>) = pts
                    .iter()
                    .map(|q| (*q, (q - x).norm()))
                    .filter(|(_, d)| *d < 100.0 && *d > 1e-9)
                    .unzip();
                assert_eq!(scan_measured(&x, &near, &dists, 100.0, &p), a);
                kinds.insert((a.arcs.len().min(3), a.surrounded));
                binned_ran += 1;
            }
        }
        // Empty, continuous, discontinuous and surrounded views were all compared.
        assert!(kinds.len() >= 4, "{kinds:?} over {binned_ran} scans");
    }
}
