//! Plane geometry used by the world (collision checks, sensing) and by behaviours.

pub type Vec2 = nalgebra::Vector2<f64>;

pub fn v2(p: [f64; 2]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// Cross product z-component of a and b.
pub fn cross(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Parameter t in [0, 1] along segment p->p+d where it first meets segment a-b, if it does.
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

/// Even-odd point-in-polygon test.
pub fn point_in_polygon(p: Vec2, poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (xi, yi) = (poly[i][0], poly[i][1]);
        let (xj, yj) = (poly[j][0], poly[j][1]);
        if (yi > p.y) != (yj > p.y) && p.x < (xj - xi) * (p.y - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Smallest t in [0, 1] at which segment p->p+d meets the closed polygon's boundary.
pub fn polygon_hit(p: Vec2, d: Vec2, poly: &[[f64; 2]]) -> Option<f64> {
    let n = poly.len();
    let mut best: Option<f64> = None;
    for i in 0..n {
        let a = v2(poly[i]);
        let b = v2(poly[(i + 1) % n]);
        if let Some(t) = segment_hit(p, d, a, b) {
            best = Some(best.map_or(t, |x: f64| x.min(t)));
        }
    }
    best
}

/// Points along the closed polygon's boundary with spacing at most `spacing`; vertices included.
pub fn sample_boundary(poly: &[[f64; 2]], spacing: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let n = poly.len();
    for i in 0..n {
        let a = v2(poly[i]);
        let b = v2(poly[(i + 1) % n]);
        let len = (b - a).norm();
        let steps = (len / spacing).ceil().max(1.0) as usize;
        for s in 0..steps {
            let q = a + (b - a) * (s as f64 / steps as f64);
            out.push([q.x, q.y]);
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
pub fn polygon_distance(q: Vec2, poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| point_segment_distance(q, v2(poly[i]), v2(poly[(i + 1) % n])))
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
}
