//! Plane geometry for the world (collision checks, sensing) and for every behaviour's kernels:
//! the one `Vec2`, the angle of a vector (the search paper's ⟨v⟩), the angle wrap F of its
//! eqs. (12)-(14), segment and polygon tests, and polygon boundary sampling (spec 5 item 1).
//!
//! Polygons are closed rings given without repeating the first vertex, as `[f64; 2]` points
//! (the scenario's) or as `Vec2`s (the kernels' tests): the polygon functions take either.

use std::f64::consts::{PI, TAU};

/// A 2-D vector / point (the search paper's X_i, V_i, B_s, P_j, Q1, Q2 ...).
pub type Vec2 = nalgebra::Vector2<f64>;

/// The point `p` as a vector (`Vec2::new(x, y)` builds one from two numbers).
pub fn v2(p: [f64; 2]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// Cross product z-component of a and b.
pub fn cross(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// ⟨v⟩: the angle of `v` to the x-axis, counter-clockwise, in (-π, π].
/// The zero vector has angle 0.
pub fn angle_of(v: &Vec2) -> f64 {
    v.y.atan2(v.x)
}

/// Unit vector with angle `a`: (cos a, sin a) as in eqs. (4) and (15) of the search paper.
pub fn unit_from_angle(a: f64) -> Vec2 {
    Vec2::new(a.cos(), a.sin())
}

/// Angle wrap F, eqs. (12)-(14) of the search paper, valid for every finite `theta`
/// (the paper restricts it to -2π < θ < 2π). Result lies in (-π, π].
///
/// The literal formula maps θ = -π to -π; this function maps it to +π so the
/// range really is (-π, π] (see [`wrap_angle_paper`]).
pub fn wrap_angle(theta: f64) -> f64 {
    let r = theta.rem_euclid(TAU); // [0, 2π] (2π possible through rounding)
    if r > PI {
        r - TAU
    } else {
        r
    }
}

/// The literal eq. (12): F(θ) = θ − 2π·sgn(θ)·δ(|θ| − π), for -2π < θ < 2π,
/// with sgn of eq. (13) and the step δ of eq. (14). Kept for reference and
/// tests; kernels use [`wrap_angle`].
pub fn wrap_angle_paper(theta: f64) -> f64 {
    let sgn = if theta < 0.0 {
        -1.0
    } else if theta > 0.0 {
        1.0
    } else {
        0.0
    }; // eq. (13)
    let delta = if theta.abs() - PI > 0.0 { 1.0 } else { 0.0 }; // eq. (14)
    theta - TAU * sgn * delta // eq. (12)
}

/// F(⟨a⟩ − ⟨b⟩): signed rotation from `b` to `a`, in (-π, π].
/// Positive = counter-clockwise.
pub fn angle_between(a: &Vec2, b: &Vec2) -> f64 {
    wrap_angle(angle_of(a) - angle_of(b))
}

/// Rescale `v` so that ‖v‖ ≤ `max` (direction kept).
pub fn clamp_norm(v: Vec2, max: f64) -> Vec2 {
    let n = v.norm();
    if n > max && n > 0.0 {
        v * (max / n)
    } else {
        v
    }
}

/// Rotates `v` counter-clockwise by `a` radians.
pub fn rotate(v: &Vec2, a: f64) -> Vec2 {
    let (s, c) = a.sin_cos();
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Parameter t in [0, 1] along segment p->p+d where it first meets segment a-b, if it does
/// (touching end points and collinear overlaps count).
pub fn segment_hit(p: Vec2, d: Vec2, a: Vec2, b: Vec2) -> Option<f64> {
    let e = b - a;
    let denom = cross(d, e);
    let ap = a - p;
    if denom.abs() < 1e-12 {
        // Parallel: treat collinear overlap as a hit at the nearest overlapping point.
        if cross(ap, d).abs() > 1e-9 {
            return None;
        }
        let dd = d.dot(&d);
        if dd < 1e-18 {
            return None;
        }
        let ta = ap.dot(&d) / dd;
        let tb = (b - p).dot(&d) / dd;
        let (lo, hi) = if ta < tb { (ta, tb) } else { (tb, ta) };
        if hi < 0.0 || lo > 1.0 {
            return None;
        }
        return Some(lo.max(0.0));
    }
    let t = cross(ap, e) / denom;
    let u = cross(ap, d) / denom;
    if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
        Some(t)
    } else {
        None
    }
}

/// Even-odd (ray casting) point-in-polygon test. Points exactly on an edge may go either
/// way; fewer than 3 vertices enclose nothing.
pub fn point_in_polygon<P: Copy + Into<Vec2>>(p: Vec2, poly: &[P]) -> bool {
    let n = poly.len();
    if n < 3 {
        return false;
    }
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (vi, vj): (Vec2, Vec2) = (poly[i].into(), poly[j].into());
        let (xi, yi) = (vi.x, vi.y);
        let (xj, yj) = (vj.x, vj.y);
        if (yi > p.y) != (yj > p.y) && p.x < (xj - xi) * (p.y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Smallest t in [0, 1] at which segment p->p+d meets the closed polygon's boundary.
pub fn polygon_hit<P: Copy + Into<Vec2>>(p: Vec2, d: Vec2, poly: &[P]) -> Option<f64> {
    let n = poly.len();
    let mut best: Option<f64> = None;
    for i in 0..n {
        let a = poly[i].into();
        let b = poly[(i + 1) % n].into();
        if let Some(t) = segment_hit(p, d, a, b) {
            best = Some(best.map_or(t, |x: f64| x.min(t)));
        }
    }
    best
}

/// True if segment [a,b] touches an edge of `poly` or lies inside it
/// (tests use it to catch a robot's step through an obstacle).
pub fn segment_hits_polygon<P: Copy + Into<Vec2>>(a: Vec2, b: Vec2, poly: &[P]) -> bool {
    polygon_hit(a, b - a, poly).is_some() || point_in_polygon(a, poly) || point_in_polygon(b, poly)
}

/// Points along the closed polygon's boundary with spacing at most `spacing` (> 0), in the
/// polygon's point type; every vertex included (spec 5 item 1 suggests spacing <= 2).
pub fn sample_boundary<P: Copy + Into<Vec2> + From<Vec2>>(poly: &[P], spacing: f64) -> Vec<P> {
    assert!(spacing > 0.0, "spacing must be positive");
    let mut out = Vec::new();
    let n = poly.len();
    for i in 0..n {
        let a: Vec2 = poly[i].into();
        let b: Vec2 = poly[(i + 1) % n].into();
        let len = (b - a).norm();
        let steps = (len / spacing).ceil().max(1.0) as usize;
        for s in 0..steps {
            out.push(P::from(a + (b - a) * (s as f64 / steps as f64)));
        }
    }
    out
}

/// Distance from point q to segment a-b.
pub fn point_segment_distance(q: Vec2, a: Vec2, b: Vec2) -> f64 {
    let e = b - a;
    let ee = e.dot(&e);
    let t = if ee < 1e-18 {
        0.0
    } else {
        ((q - a).dot(&e) / ee).clamp(0.0, 1.0)
    };
    (a + e * t - q).norm()
}

/// Distance from q to the closed polygon's boundary.
pub fn polygon_distance<P: Copy + Into<Vec2>>(q: Vec2, poly: &[P]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| point_segment_distance(q, poly[i].into(), poly[(i + 1) % n].into()))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];

    #[test]
    fn segment_crossing_a_square_hits_its_near_side() {
        let t = polygon_hit(Vec2::new(-5.0, 5.0), Vec2::new(10.0, 0.0), &SQUARE).unwrap();
        assert!((t - 0.5).abs() < 1e-12);
        assert!(polygon_hit(Vec2::new(-5.0, 5.0), Vec2::new(4.0, 0.0), &SQUARE).is_none());
    }

    #[test]
    fn a_segment_passing_through_a_thin_wall_is_caught() {
        // Both end points are outside: only a whole-segment check sees the crossing.
        let wall = [[5.0, -10.0], [5.5, -10.0], [5.5, 10.0], [5.0, 10.0]];
        let p = Vec2::new(0.0, 0.0);
        let d = Vec2::new(10.0, 0.0);
        assert!(!point_in_polygon(p + d, &wall));
        assert!(polygon_hit(p, d, &wall).is_some());
    }

    #[test]
    fn point_in_polygon_inside_and_outside() {
        assert!(point_in_polygon(Vec2::new(5.0, 5.0), &SQUARE));
        assert!(!point_in_polygon(Vec2::new(15.0, 5.0), &SQUARE));
        assert!(!point_in_polygon::<[f64; 2]>(Vec2::new(0.0, 0.0), &[]));
    }

    #[test]
    fn boundary_sampling_respects_spacing() {
        let pts = sample_boundary(&SQUARE, 2.0);
        assert_eq!(pts.len(), 20);
        for w in pts.windows(2) {
            let d = (v2(w[1]) - v2(w[0])).norm();
            assert!(d <= 2.0 + 1e-9, "gap {d}");
        }
    }

    #[test]
    fn wrap_maps_into_half_open_interval() {
        let cases = [
            (0.0, 0.0),
            (PI, PI),
            (-PI, PI),
            (1.5 * PI, -0.5 * PI),
            (-1.5 * PI, 0.5 * PI),
            (TAU - 0.1, -0.1),
            (-TAU + 0.1, 0.1),
            (5.0 * PI + 0.3, -PI + 0.3),
            (0.1, 0.1),
        ];
        for (theta, want) in cases {
            let got = wrap_angle(theta);
            assert!((got - want).abs() < 1e-9, "F({theta}) = {got}, want {want}");
            assert!(got > -PI && got <= PI);
        }
    }

    #[test]
    fn wrap_agrees_with_literal_eq12_inside_its_domain() {
        let mut theta = -TAU + 1e-3;
        while theta < TAU {
            if (theta + PI).abs() > 1e-9 {
                let (a, b) = (wrap_angle(theta), wrap_angle_paper(theta));
                assert!((a - b).abs() < 1e-9, "θ={theta}: {a} vs {b}");
            }
            theta += 0.0137;
        }
        // The literal formula keeps -π (outside (-π, π]); ours maps it to π.
        assert_eq!(wrap_angle_paper(-PI), -PI);
        assert_eq!(wrap_angle(-PI), PI);
    }

    #[test]
    fn angle_between_sign_is_ccw_positive() {
        let east = Vec2::new(1.0, 0.0);
        let north = Vec2::new(0.0, 1.0);
        assert!((angle_between(&north, &east) - PI / 2.0).abs() < 1e-12);
        assert!((angle_between(&east, &north) + PI / 2.0).abs() < 1e-12);
        // across the ±π seam
        let a = Vec2::new(-1.0, 0.01);
        let b = Vec2::new(-1.0, -0.01);
        // a is just above west, b just below: b is 0.02 rad counter-clockwise of a.
        assert!(angle_between(&b, &a) > 0.0 && angle_between(&b, &a) < 0.1);
        assert!(angle_between(&a, &b) < 0.0 && angle_between(&a, &b) > -0.1);
    }

    #[test]
    fn segment_hit_cases() {
        let hit = |a1: [f64; 2], a2: [f64; 2], b1: [f64; 2], b2: [f64; 2]| {
            segment_hit(v2(a1), v2(a2) - v2(a1), v2(b1), v2(b2)).is_some()
        };
        let o = [0.0, 0.0];
        assert!(hit(o, [2.0, 2.0], [0.0, 2.0], [2.0, 0.0]));
        assert!(!hit(o, [1.0, 1.0], [0.0, 3.0], [3.0, 2.5]));
        // touching at an end point
        assert!(hit(o, [1.0, 0.0], [1.0, 0.0], [1.0, 5.0]));
        // collinear overlap and collinear disjoint
        assert!(hit(o, [2.0, 0.0], [1.0, 0.0], [3.0, 0.0]));
        assert!(!hit(o, [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]));
        // parallel
        assert!(!hit(o, [2.0, 0.0], [0.0, 1.0], [2.0, 1.0]));
    }

    fn u_shape() -> Vec<Vec2> {
        [
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [8.0, 10.0],
            [8.0, 2.0],
            [2.0, 2.0],
            [2.0, 10.0],
            [0.0, 10.0],
        ]
        .map(v2)
        .to_vec()
    }

    #[test]
    fn point_in_nonconvex_polygon() {
        let u = u_shape();
        assert!(point_in_polygon(Vec2::new(1.0, 5.0), &u));
        assert!(point_in_polygon(Vec2::new(5.0, 1.0), &u));
        assert!(!point_in_polygon(Vec2::new(5.0, 5.0), &u)); // in the cavity
        assert!(!point_in_polygon(Vec2::new(-1.0, 5.0), &u));
        assert!(!point_in_polygon(Vec2::new(5.0, 11.0), &u));
    }

    #[test]
    fn segment_vs_polygon() {
        let u = u_shape();
        let hits = |a: [f64; 2], b: [f64; 2]| segment_hits_polygon(v2(a), v2(b), &u);
        // fully inside the cavity: no hit
        assert!(!hits([4.0, 4.0], [6.0, 8.0]));
        // crosses the left arm
        assert!(hits([-1.0, 5.0], [5.0, 5.0]));
        // entirely inside the solid bottom
        assert!(hits([3.0, 1.0], [4.0, 1.5]));
        // passes above
        assert!(!hits([-5.0, 11.0], [15.0, 11.0]));
    }

    #[test]
    fn boundary_sampling_spacing_and_vertices() {
        let u = u_shape();
        for spacing in [2.0, 0.7, 3.0] {
            let pts = sample_boundary(&u, spacing);
            for i in 0..pts.len() {
                let d = (pts[(i + 1) % pts.len()] - pts[i]).norm();
                assert!(d <= spacing + 1e-9, "gap {d} > {spacing}");
                assert!(d > 0.0);
            }
            for vtx in &u {
                assert!(pts.iter().any(|p| (p - vtx).norm() < 1e-12));
            }
        }
    }

    #[test]
    fn rotate_a_quarter_turn() {
        let r = rotate(&Vec2::new(1.0, 0.0), PI / 2.0);
        assert!((r - Vec2::new(0.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn clamp_norm_rescales_only_when_needed() {
        assert_eq!(clamp_norm(Vec2::new(3.0, 4.0), 10.0), Vec2::new(3.0, 4.0));
        let c = clamp_norm(Vec2::new(30.0, 40.0), 10.0);
        assert!((c.norm() - 10.0).abs() < 1e-12 && (c.x - 6.0).abs() < 1e-12);
        assert_eq!(clamp_norm(Vec2::zeros(), 10.0), Vec2::zeros());
    }
}
