//! Planar geometry helpers shared by every kernel: the angle of a vector
//! (the paper's ⟨v⟩), the angle wrap F of eqs. (12)-(14), segment and
//! polygon tests, and polygon boundary sampling (spec §5 item 1).

use nalgebra::Vector2;
use std::f64::consts::{PI, TAU};

/// A 2-D vector / point (paper: X_i, V_i, B_s, P_j, Q1, Q2 ...).
pub type Vec2 = Vector2<f64>;

/// Tolerance used by the orientation tests below.
const EPS: f64 = 1e-12;

/// Shorthand constructor.
pub fn v2(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

/// ⟨v⟩: the angle of `v` to the x-axis, counter-clockwise, in (-π, π].
/// The zero vector has angle 0.
pub fn angle_of(v: &Vec2) -> f64 {
    v.y.atan2(v.x)
}

/// Unit vector with angle `a`: (cos a, sin a) as in eqs. (4) and (15).
pub fn unit_from_angle(a: f64) -> Vec2 {
    v2(a.cos(), a.sin())
}

/// Angle wrap F, eqs. (12)-(14), valid for every finite `theta`
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

/// 2-D cross product (z component).
pub fn cross(a: &Vec2, b: &Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

fn orient(a: &Vec2, b: &Vec2, c: &Vec2) -> f64 {
    cross(&(b - a), &(c - a))
}

fn on_segment(a: &Vec2, b: &Vec2, p: &Vec2) -> bool {
    p.x >= a.x.min(b.x) - EPS
        && p.x <= a.x.max(b.x) + EPS
        && p.y >= a.y.min(b.y) - EPS
        && p.y <= a.y.max(b.y) + EPS
}

/// True if closed segments [a1,a2] and [b1,b2] share at least one point
/// (proper crossings, touching end points and collinear overlaps).
pub fn segments_intersect(a1: &Vec2, a2: &Vec2, b1: &Vec2, b2: &Vec2) -> bool {
    let d1 = orient(b1, b2, a1);
    let d2 = orient(b1, b2, a2);
    let d3 = orient(a1, a2, b1);
    let d4 = orient(a1, a2, b2);
    if ((d1 > EPS && d2 < -EPS) || (d1 < -EPS && d2 > EPS))
        && ((d3 > EPS && d4 < -EPS) || (d3 < -EPS && d4 > EPS))
    {
        return true;
    }
    (d1.abs() <= EPS && on_segment(b1, b2, a1))
        || (d2.abs() <= EPS && on_segment(b1, b2, a2))
        || (d3.abs() <= EPS && on_segment(a1, a2, b1))
        || (d4.abs() <= EPS && on_segment(a1, a2, b2))
}

/// Even-odd (ray casting) point-in-polygon test. `poly` is a closed ring
/// given without repeating the first vertex. Points exactly on an edge may
/// go either way.
pub fn point_in_polygon(p: &Vec2, poly: &[Vec2]) -> bool {
    let n = poly.len();
    if n < 3 {
        return false;
    }
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (pi, pj) = (&poly[i], &poly[j]);
        if (pi.y > p.y) != (pj.y > p.y) {
            let x_cross = pj.x + (p.y - pj.y) * (pi.x - pj.x) / (pi.y - pj.y);
            if p.x < x_cross {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// True if segment [a,b] touches an edge of `poly` or lies inside it
/// (used by simulators and tests to detect a robot step through an obstacle).
pub fn segment_hits_polygon(a: &Vec2, b: &Vec2, poly: &[Vec2]) -> bool {
    let n = poly.len();
    if n == 0 {
        return false;
    }
    for i in 0..n {
        let (p, q) = (&poly[i], &poly[(i + 1) % n]);
        if segments_intersect(a, b, p, q) {
            return true;
        }
    }
    point_in_polygon(a, poly) || point_in_polygon(b, poly)
}

/// Distance from point `p` to the closed segment [a,b].
pub fn point_segment_distance(p: &Vec2, a: &Vec2, b: &Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 <= 0.0 {
        return (p - a).norm();
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Rotates `v` counter-clockwise by `a` radians.
pub fn rotate(v: &Vec2, a: f64) -> Vec2 {
    let (s, c) = a.sin_cos();
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Distance along unit vector `u` to the first of `pts` lying in the
/// corridor of half-width `hw` ahead of `x` (0 < along < `reach`), if any.
pub fn blocked_at(x: &Vec2, u: &Vec2, pts: &[Vec2], hw: f64, reach: f64) -> Option<f64> {
    pts.iter()
        .map(|b| b - x)
        .filter(|r| {
            let along = r.dot(u);
            along > 0.0 && along < reach && cross(u, r).abs() < hw
        })
        .map(|r| r.dot(u))
        .min_by(f64::total_cmp)
}

/// Samples the boundary of the closed polygon `poly` into points so that
/// consecutive points (including last→first) are at most `spacing` apart
/// (spec §5 item 1 suggests spacing ≤ 2). Every vertex is included.
pub fn sample_polygon_boundary(poly: &[Vec2], spacing: f64) -> Vec<Vec2> {
    assert!(spacing > 0.0, "spacing must be positive");
    let n = poly.len();
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let len = (b - a).norm();
        let pieces = ((len / spacing).ceil() as usize).max(1);
        for k in 0..pieces {
            out.push(a + (b - a) * (k as f64 / pieces as f64));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let east = v2(1.0, 0.0);
        let north = v2(0.0, 1.0);
        assert!((angle_between(&north, &east) - PI / 2.0).abs() < 1e-12);
        assert!((angle_between(&east, &north) + PI / 2.0).abs() < 1e-12);
        // across the ±π seam
        let a = v2(-1.0, 0.01);
        let b = v2(-1.0, -0.01);
        // a is just above west, b just below: b is 0.02 rad counter-clockwise of a.
        assert!(angle_between(&b, &a) > 0.0 && angle_between(&b, &a) < 0.1);
        assert!(angle_between(&a, &b) < 0.0 && angle_between(&a, &b) > -0.1);
    }

    #[test]
    fn segment_intersection_cases() {
        let o = v2(0.0, 0.0);
        assert!(segments_intersect(
            &o,
            &v2(2.0, 2.0),
            &v2(0.0, 2.0),
            &v2(2.0, 0.0)
        ));
        assert!(!segments_intersect(
            &o,
            &v2(1.0, 1.0),
            &v2(0.0, 3.0),
            &v2(3.0, 2.5)
        ));
        // touching at an end point
        assert!(segments_intersect(
            &o,
            &v2(1.0, 0.0),
            &v2(1.0, 0.0),
            &v2(1.0, 5.0)
        ));
        // collinear overlap and collinear disjoint
        assert!(segments_intersect(
            &o,
            &v2(2.0, 0.0),
            &v2(1.0, 0.0),
            &v2(3.0, 0.0)
        ));
        assert!(!segments_intersect(
            &o,
            &v2(1.0, 0.0),
            &v2(2.0, 0.0),
            &v2(3.0, 0.0)
        ));
        // parallel
        assert!(!segments_intersect(
            &o,
            &v2(2.0, 0.0),
            &v2(0.0, 1.0),
            &v2(2.0, 1.0)
        ));
    }

    fn u_shape() -> Vec<Vec2> {
        vec![
            v2(0.0, 0.0),
            v2(10.0, 0.0),
            v2(10.0, 10.0),
            v2(8.0, 10.0),
            v2(8.0, 2.0),
            v2(2.0, 2.0),
            v2(2.0, 10.0),
            v2(0.0, 10.0),
        ]
    }

    #[test]
    fn point_in_nonconvex_polygon() {
        let u = u_shape();
        assert!(point_in_polygon(&v2(1.0, 5.0), &u));
        assert!(point_in_polygon(&v2(5.0, 1.0), &u));
        assert!(!point_in_polygon(&v2(5.0, 5.0), &u)); // in the cavity
        assert!(!point_in_polygon(&v2(-1.0, 5.0), &u));
        assert!(!point_in_polygon(&v2(5.0, 11.0), &u));
    }

    #[test]
    fn segment_vs_polygon() {
        let u = u_shape();
        // fully inside the cavity: no hit
        assert!(!segment_hits_polygon(&v2(4.0, 4.0), &v2(6.0, 8.0), &u));
        // crosses the left arm
        assert!(segment_hits_polygon(&v2(-1.0, 5.0), &v2(5.0, 5.0), &u));
        // entirely inside the solid bottom
        assert!(segment_hits_polygon(&v2(3.0, 1.0), &v2(4.0, 1.5), &u));
        // passes above
        assert!(!segment_hits_polygon(&v2(-5.0, 11.0), &v2(15.0, 11.0), &u));
    }

    #[test]
    fn boundary_sampling_spacing_and_vertices() {
        let u = u_shape();
        for spacing in [2.0, 0.7, 3.0] {
            let pts = sample_polygon_boundary(&u, spacing);
            for i in 0..pts.len() {
                let d = (pts[(i + 1) % pts.len()] - pts[i]).norm();
                assert!(d <= spacing + 1e-9, "gap {d} > {spacing}");
                assert!(d > 0.0);
            }
            for vtx in &u {
                assert!(pts.iter().any(|p| (p - vtx).norm() < 1e-12));
            }
        }
        // a 10x10 square at spacing 2 -> 5 points per side
        let sq = [v2(0.0, 0.0), v2(10.0, 0.0), v2(10.0, 10.0), v2(0.0, 10.0)];
        assert_eq!(sample_polygon_boundary(&sq, 2.0).len(), 20);
    }

    #[test]
    fn rotate_and_corridor() {
        let r = rotate(&v2(1.0, 0.0), PI / 2.0);
        assert!((r - v2(0.0, 1.0)).norm() < 1e-12);
        let pts = [v2(5.0, 1.5), v2(3.0, -3.0), v2(-2.0, 0.0), v2(20.0, 0.0)];
        let u = v2(1.0, 0.0);
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 2.0, 12.0), Some(5.0));
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 1.0, 12.0), None);
    }

    #[test]
    fn clamp_norm_rescales_only_when_needed() {
        assert_eq!(clamp_norm(v2(3.0, 4.0), 10.0), v2(3.0, 4.0));
        let c = clamp_norm(v2(30.0, 40.0), 10.0);
        assert!((c.norm() - 10.0).abs() < 1e-12 && (c.x - 6.0).abs() < 1e-12);
        assert_eq!(clamp_norm(Vec2::zeros(), 10.0), Vec2::zeros());
    }
}
