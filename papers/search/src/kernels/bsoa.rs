//! BSOA, the boundary-scan obstacle-avoidance strategy (paper §3.4, Figs. 3-4,
//! Table 2, eqs. (12)-(22); spec §2.8), with the errata resolved as spec §5
//! items 18-21 and §6 items 2-5 suggest.
//!
//! Input: robot position X_i(t), desired velocity V_if(t+1), sensed obstacle
//! points, and the rotation-sense flag SF of the previous step. Output: the
//! velocity V_i(t+1) and the new SF.

use agent::kernels::boundary::{self, Scan};
use agent::kernels::nearest::TwoNearest;
use agent::kernels::obstacles::blocked_at;
use agent::kernels::virtual_force;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use swarm::geometry::{angle_between, angle_of, cross, rotate, unit_from_angle, wrap_angle, Vec2};

/// SF, the avoidance flag of Table 2 / eq. (22).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sense {
    /// SF = 0: no avoidance at the last step.
    #[default]
    None,
    /// SF = 1: clockwise avoidance at the last step (F(⟨V_i⟩ − ⟨V_if⟩) < 0).
    Clockwise,
    /// SF = 2: counter-clockwise avoidance at the last step (F > 0).
    CounterClockwise,
}

impl Sense {
    /// The paper's numeric code 0 / 1 / 2.
    pub fn code(self) -> u8 {
        match self {
            Sense::None => 0,
            Sense::Clockwise => 1,
            Sense::CounterClockwise => 2,
        }
    }

    /// Eq. (22) with its erratum fixed (spec §6 item 4, §5 item 19):
    /// SF = [F < 0] + 2·[F > 0], F = F(⟨V_i(t+1)⟩ − ⟨V_if(t+1)⟩), i.e.
    /// 1 = clockwise and 2 = counter-clockwise as the text defines them.
    pub fn from_rotation(f: f64) -> Sense {
        if f < 0.0 {
            Sense::Clockwise
        } else if f > 0.0 {
            Sense::CounterClockwise
        } else {
            Sense::None
        }
    }
}

/// Which branch of Table 2 produced the velocity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// No obstacle in the desired direction: V_i = V_if (Table 2 line 16).
    Free,
    /// Case 1, ‖Q1 − X‖ ≤ l_2: slide along ±(Q1 − Q2) (eqs. 16-17).
    Forced,
    /// Case 2a, N_P = 2: head for boundary point P_j1 (eqs. 18-19).
    Continuous,
    /// Case 2b, N_P > 2: force-weighted heading into the gap j1-j2 (eqs. 20-21).
    Discontinuous,
    /// N_P = 0 (obstacle all around): case 1 fallback (spec §5 item 20).
    Surrounded,
}

/// BSOA result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// V_i(t+1).
    pub velocity: Vec2,
    /// SF after this step (eq. 22, corrected).
    pub sense: Sense,
    /// Branch taken.
    pub case: Case,
}

/// Tunables of BSOA.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Maximum speed V_max = 10; avoidance always flies at V_max (eq. 15, Table 4).
    pub v_max: f64,
    /// Obstacle sensing radius L_B = 100 (Table 4; Table 2 line 1).
    pub l_b: f64,
    /// Target sensing radius L_T = 100; only obstacles within it are
    /// considered (paper §3.4, Table 2 line 1).
    pub l_t: f64,
    /// Forced-avoidance distance l_2 = 10 (Table 4, case 1).
    pub l_2: f64,
    /// Heading tolerance of the trigger, read as |F(⟨V_if⟩ − ⟨B_s − X⟩)| <
    /// 0.1 rad (Table 2 line 1). [chosen] spec §5 item 21, §6 item 5.
    pub heading_tolerance: f64,
    /// Extra trigger: an obstacle point ahead whose perpendicular distance to
    /// the V_if ray is below this also counts as "in the desired direction"
    /// (2.0 = sample spacing, so a sampled wall crossing the ray is always
    /// seen; the 0.1 rad cone alone misses walls closer than ~10).
    /// [chosen] spec §5 items 21-22.
    pub corridor_half_width: f64,
    /// Virtual-force coefficient c = 3.9 for the eq. (21) weights (Table 4, eq. 5).
    pub c: f64,
    /// Enhanced obstacle-avoidance distance l_1 = 10 for the eq. (21)
    /// weights (Table 4, eq. 5).
    pub l_1: f64,
    /// In case 1, check the slide direction for obstacle points within
    /// V_max + corridor_half_width ahead (concave corners) and turn away
    /// from the obstacle if blocked (true). [chosen] spec §5 item 22.
    pub forced_lookahead: bool,
    /// Boundary-point extraction settings. [chosen] spec §5 item 20.
    pub boundary: boundary::Params,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            v_max: 10.0,
            l_b: 100.0,
            l_t: 100.0,
            l_2: 10.0,
            heading_tolerance: 0.1,
            corridor_half_width: 2.0,
            c: 3.9,
            l_1: 10.0,
            forced_lookahead: true,
            boundary: boundary::Params::default(),
        }
    }
}

impl Params {
    fn force(&self) -> virtual_force::Params {
        virtual_force::Params {
            c: self.c,
            l1: self.l_1,
            l_b: self.l_b,
            v_max: self.v_max,
            ..virtual_force::Params::default()
        }
    }
}

/// Table 2 line 1 (with |F(·)|, spec §6 item 5) plus the corridor test:
/// is some obstacle point in the direction of `v_if`?
pub fn obstacle_ahead(x: &Vec2, v_if: &Vec2, pts: &[Vec2], tol: f64, half_width: f64) -> bool {
    let u = v_if.normalize();
    let heading = angle_of(v_if);
    // Most points lie far outside the heading cone; a test without atan2 rules them out. Its
    // margin (1e-6 rad) is ~10^9 times the rounding of the angles, so every point it rules out
    // fails the exact test too, and the result is the same bit for bit.
    let margin = 1e-6;
    let cone = (tol + margin < 1.0).then(|| (tol + margin).tan());
    pts.iter().any(|b| {
        let r = b - x;
        // (A zero v_if makes u NaN: nothing is ruled out.)
        let outside = cone.is_some_and(|t| {
            let along = u.dot(&r);
            along <= 0.0 || cross(u, r).abs() > along * t
        });
        (!outside && wrap_angle(heading - angle_of(&r)).abs() < tol)
            || (r.dot(&u) > 0.0 && cross(u, r).abs() < half_width)
    })
}

/// Sense implied by which side of the motion direction `t` the nearest
/// obstacle point lies on: obstacle on the left ⇔ the robot is turning
/// clockwise around it (SF = 1), on the right ⇔ counter-clockwise (SF = 2).
fn side_sense(t: &Vec2, to_q1: &Vec2) -> Sense {
    Sense::from_rotation(-cross(*t, *to_q1))
}

/// Case 1, eqs. (16)-(17) in reading (B) of spec §2.8 (erratum §6 item 2):
/// slide along the line through the two nearest obstacle points,
/// a = ⟨±(Q1 − Q2)⟩. The sign (spec §5 item 18) keeps the obstacle on the
/// same side as the previous step's rotation sense (SF = 1: obstacle on the
/// left; SF = 2: on the right); with SF = 0 it is the sign closer to V_if.
/// With a single point the line is the tangent ⊥ (Q1 − X). Returns the
/// heading and the sense it implies.
fn forced_heading(x: &Vec2, v_if: &Vec2, near: &[Vec2], prev: Sense, p: &Params) -> (f64, Sense) {
    let q1 = near[0];
    let to_q1 = q1 - x;
    let line = match near.get(1) {
        Some(q2) if (q1 - q2).norm() > 1e-9 => q1 - q2,
        _ => Vec2::new(-to_q1.y, to_q1.x),
    }
    .normalize();
    let cands = [line, -line];
    let rel = cands.map(|t| angle_between(&t, v_if).abs());
    let closer = if rel[0] <= rel[1] { 0 } else { 1 };
    let k = match prev {
        Sense::None => closer,
        s => (0..2)
            .find(|&k| side_sense(&cands[k], &to_q1) == s)
            .unwrap_or(closer),
    };
    let mut t = cands[k];
    let mut sense = side_sense(&t, &to_q1);
    if sense == Sense::None {
        sense = Sense::from_rotation(angle_between(&t, v_if));
    }
    if p.forced_lookahead {
        // [chosen] spec §5 item 22: if the slide would run into obstacle points
        // ahead (a concave corner), turn away from the obstacle side in 45°
        // steps; if every direction is blocked take the one blocked farthest.
        let away = if sense == Sense::CounterClockwise {
            1.0
        } else {
            -1.0
        };
        let reach = p.v_max + p.corridor_half_width;
        let mut best = (t, 0.0);
        for step in 0..5 {
            let u = rotate(&t, away * step as f64 * PI / 4.0);
            match blocked_at(x, &u, near, p.corridor_half_width, reach) {
                None => {
                    best = (u, f64::INFINITY);
                    break;
                }
                Some(d) if d > best.1 => best = (u, d),
                Some(_) => {}
            }
        }
        t = best.0;
    }
    (angle_of(&t), sense)
}

/// j1 of eq. (18) (spec §6 item 3): SF = 0 → the boundary point angularly
/// closest to V_if; SF = 1 → the closest one on the clockwise side (largest
/// negative F); SF = 2 → the closest on the counter-clockwise side. Falls
/// back to the SF = 0 rule when that side is empty (spec §5 item 19).
fn choose_j1(scan: &Scan, heading: f64, prev: Sense) -> usize {
    let rel: Vec<f64> = (0..scan.n_p())
        .map(|j| wrap_angle(scan.boundary_angle(j) - heading))
        .collect();
    let by = |a: &usize, b: &usize, key: &dyn Fn(usize) -> f64| {
        key(*a).total_cmp(&key(*b)).then(b.cmp(a))
    };
    let side = match prev {
        Sense::Clockwise => (0..rel.len())
            .filter(|&j| rel[j] < 0.0)
            .max_by(|a, b| by(a, b, &|j| rel[j])),
        Sense::CounterClockwise => (0..rel.len())
            .filter(|&j| rel[j] > 0.0)
            .max_by(|a, b| by(a, b, &|j| -rel[j])),
        Sense::None => None,
    };
    side.unwrap_or_else(|| {
        (0..rel.len())
            .max_by(|a, b| by(a, b, &|j| -rel[j].abs()))
            .expect("at least one boundary point")
    })
}

/// Moves the points at `i1` and `i2` (the nearest and second nearest; `i2` may be
/// `usize::MAX` when there is one point) to places 0 and 1; the rest keep no order.
fn to_front<T>(pts: &mut [T], i1: usize, i2: usize) {
    pts.swap(0, i1);
    if i2 < pts.len() {
        // If Q2 was at place 0 it has just moved to i1.
        let i2 = if i2 == 0 { i1 } else { i2 };
        pts.swap(1, i2);
    }
}

/// Cases 3 and 4 of Table 2: head for boundary point j1 (eqs. 18-19) or between j1 and its
/// gap partner j2 (eqs. 20-21).
fn discontinuous_or_continuous(
    x: &Vec2,
    scan: &Scan,
    heading: f64,
    prev: Sense,
    p: &Params,
) -> (f64, Option<Sense>, Case) {
    let j1 = choose_j1(scan, heading, prev);
    let b1 = scan.boundary_angle(j1); // eq. (18)
    if scan.is_continuous() || scan.gap_width(j1) > PI {
        // eq. (19). A free gap wider than π (only possible behind the
        // robot) would make eq. (21) bisect through the obstacles, so it
        // is treated like the continuous case. [chosen]
        (b1, None, Case::Continuous)
    } else {
        let j2 = scan.gap_partner(j1);
        let b2 = scan.boundary_angle(j2); // eq. (20)
        let bp = scan.boundary_points();
        let f = p.force();
        let f1 = virtual_force::magnitude((bp[j1] - x).norm(), p.l_b, &f);
        let f2 = virtual_force::magnitude((bp[j2] - x).norm(), p.l_b, &f);
        // eq. (21), with atan2
        let a = (f1 * b1.sin() + f2 * b2.sin()).atan2(f1 * b1.cos() + f2 * b2.cos());
        (a, None, Case::Discontinuous)
    }
}

/// One BSOA step (Table 2).
pub fn avoid(x: &Vec2, v_if: &Vec2, obstacle_points: &[Vec2], prev: Sense, p: &Params) -> Output {
    avoid_within(
        x,
        v_if,
        obstacle_points.iter().copied(),
        f64::INFINITY,
        prev,
        p,
    )
}

/// [`avoid`] counting only the obstacle points closer than `limit` (a cooperative robot's
/// horizon; INFINITY: all), straight from the sensed points, measured once.
pub fn avoid_within(
    x: &Vec2,
    v_if: &Vec2,
    obstacle_points: impl IntoIterator<Item = Vec2>,
    limit: f64,
    prev: Sense,
    p: &Params,
) -> Output {
    let free = Output {
        velocity: *v_if,
        sense: Sense::None,
        case: Case::Free,
    };
    let range = p.l_b.min(p.l_t);
    // Obstacles within L_B and L_T (paper §3.4), as a set but for the two nearest: everything
    // below uses the points in an order-free way (any / min / the angular scan's own sort)
    // except Q1 and Q2, which go to the front (ties by input order).
    let points = obstacle_points.into_iter();
    let mut pts: Vec<Vec2> = Vec::with_capacity(points.size_hint().0);
    let mut dists: Vec<f64> = Vec::with_capacity(points.size_hint().0);
    let mut nearest = TwoNearest::default();
    for b in points {
        let d = (b - x).norm();
        if d < range && d > 1e-9 && d < limit {
            nearest.offer(d, pts.len());
            pts.push(b);
            dists.push(d);
        }
    }
    if pts.is_empty() || v_if.norm() <= 1e-12 {
        return free; // Fig. 3(a) case 1 (or no desired motion)
    }
    let (q1_dist, i1) = nearest.first().expect("a point in range");
    let i2 = nearest.second().map_or(usize::MAX, |q2| q2.1);
    to_front(&mut pts, i1, i2);
    to_front(&mut dists, i1, i2);
    if !obstacle_ahead(x, v_if, &pts, p.heading_tolerance, p.corridor_half_width) {
        return free; // Fig. 3(a) case 2; Table 2 line 16
    }
    let heading = angle_of(v_if);

    let forced = |case: Case| {
        let (a, sense) = forced_heading(x, v_if, &pts, prev, p); // eqs. (16)-(17)
        (a, Some(sense), case)
    };
    // Case 1 (Q1 within l_2) needs no boundary scan; the scan serves cases 3-4 and tells a
    // surrounded robot (which case 1 then serves too).
    let (a, forced_sense, case) = if q1_dist <= p.l_2 {
        forced(Case::Forced)
    } else {
        let scan = boundary::scan_measured(x, &pts, &dists, range, &p.boundary);
        if scan.surrounded || scan.n_p() == 0 {
            forced(Case::Surrounded)
        } else {
            discontinuous_or_continuous(x, &scan, heading, prev, p)
        }
    };
    let velocity = unit_from_angle(a) * p.v_max; // eq. (15)
                                                 // eq. (22), corrected; in case 1 the side-based sense (see forced_heading)
    let sense =
        forced_sense.unwrap_or_else(|| Sense::from_rotation(angle_between(&velocity, v_if)));
    Output {
        velocity,
        sense,
        case,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::testkit::{in_box, rect, run_to_goal, u_shape};
    use swarm::geometry::sample_boundary;

    fn bsoa_runner(p: Params) -> impl FnMut(&Vec2, &Vec2, &[Vec2]) -> Vec2 {
        let mut sf = Sense::None;
        move |x, v_if, pts| {
            let o = avoid(x, v_if, pts, sf, &p);
            sf = o.sense;
            o.velocity
        }
    }

    #[test]
    fn free_when_nothing_ahead() {
        let p = Params::default();
        let wall = sample_boundary(&rect(50.0, -40.0, 54.0, 40.0), 2.0);
        // heading north, wall to the east: no avoidance
        let o = avoid(
            &Vec2::new(0.0, 0.0),
            &Vec2::new(0.0, 7.0),
            &wall,
            Sense::Clockwise,
            &p,
        );
        assert_eq!(
            (o.case, o.sense, o.velocity),
            (Case::Free, Sense::None, Vec2::new(0.0, 7.0))
        );
        // heading east into it: avoidance at full speed
        let o = avoid(
            &Vec2::new(0.0, 0.0),
            &Vec2::new(7.0, 0.0),
            &wall,
            Sense::None,
            &p,
        );
        assert_eq!(o.case, Case::Continuous);
        assert!((o.velocity.norm() - 10.0).abs() < 1e-9);
        // out of range (≥ 100): ignored
        let o = avoid(
            &Vec2::new(-60.0, 0.0),
            &Vec2::new(7.0, 0.0),
            &wall,
            Sense::None,
            &p,
        );
        assert_eq!(o.case, Case::Free);
    }

    #[test]
    fn sense_codes_follow_the_text_definition() {
        assert_eq!(Sense::from_rotation(-0.3).code(), 1);
        assert_eq!(Sense::from_rotation(0.3).code(), 2);
        assert_eq!(Sense::from_rotation(0.0).code(), 0);
    }

    #[test]
    fn continuous_case_heads_for_closer_boundary_point_and_keeps_sense() {
        let p = Params::default();
        // Wall ahead (east), longer to the north: the south end is closer in angle.
        let wall = sample_boundary(&rect(40.0, -20.0, 44.0, 60.0), 2.0);
        let x = Vec2::new(0.0, 0.0);
        let o = avoid(&x, &Vec2::new(10.0, 0.0), &wall, Sense::None, &p);
        assert_eq!(o.case, Case::Continuous);
        assert_eq!(o.sense, Sense::Clockwise);
        let want = angle_of(&(Vec2::new(40.0, -20.0) - x));
        assert!((angle_of(&o.velocity) - want).abs() < 1e-9);
        // With SF = 2 (counter-clockwise last step) it keeps turning that way.
        let o = avoid(
            &x,
            &Vec2::new(10.0, 0.0),
            &wall,
            Sense::CounterClockwise,
            &p,
        );
        assert_eq!(o.sense, Sense::CounterClockwise);
        let want = angle_of(&(Vec2::new(40.0, 60.0) - x));
        assert!((angle_of(&o.velocity) - want).abs() < 1e-9);
    }

    #[test]
    fn discontinuous_case_heads_into_the_gap_leaning_to_the_nearer_edge() {
        let p = Params::default();
        let mut pts = sample_boundary(&rect(30.0, -50.0, 34.0, 2.0), 2.0);
        pts.extend(sample_boundary(&rect(50.0, 14.0, 54.0, 60.0), 2.0));
        let x = Vec2::new(0.0, 0.0);
        let o = avoid(&x, &Vec2::new(10.0, 0.0), &pts, Sense::None, &p);
        assert_eq!(o.case, Case::Discontinuous);
        let (lo, hi) = (
            angle_of(&Vec2::new(30.0, 2.0)),
            angle_of(&Vec2::new(54.0, 14.0)),
        );
        let a = angle_of(&o.velocity);
        assert!(a > lo && a < hi, "{lo} < {a} < {hi}");
        // leans toward the nearer edge (34,2): below the angular midpoint
        assert!(a < (lo + hi) / 2.0);
    }

    #[test]
    fn forced_case_slides_along_the_wall() {
        let p = Params::default();
        let wall = sample_boundary(&rect(5.0, -50.0, 9.0, 50.0), 2.0);
        let x = Vec2::new(0.0, 0.0);
        // desired heading east-north-east: slide north (closer to V_if)
        let o = avoid(&x, &Vec2::new(10.0, 1.0), &wall, Sense::None, &p);
        assert_eq!(o.case, Case::Forced);
        assert!(
            o.velocity.x.abs() < 1e-9 && o.velocity.y > 9.99,
            "{:?}",
            o.velocity
        );
        assert_eq!(o.sense, Sense::CounterClockwise);
        // after a clockwise step it keeps clockwise: slide south
        let o = avoid(&x, &Vec2::new(10.0, 1.0), &wall, Sense::Clockwise, &p);
        assert!(o.velocity.y < -9.99, "{:?}", o.velocity);
    }

    #[test]
    fn forced_slide_turns_at_a_concave_corner() {
        use swarm::geometry::segment_hits_polygon;
        // Floor y∈[0,4] and a wall x∈[96,100]; robot 3 above the floor,
        // 6 short of the wall, desired heading into the floor.
        let polys = [rect(0.0, 0.0, 100.0, 4.0), rect(96.0, 0.0, 100.0, 100.0)];
        let pts: Vec<Vec2> = polys.iter().flat_map(|q| sample_boundary(q, 2.0)).collect();
        let x = Vec2::new(90.0, 7.0);
        let hits = |v: &Vec2| polys.iter().any(|q| segment_hits_polygon(x, x + v, q));
        let o = avoid(
            &x,
            &Vec2::new(10.0, -2.0),
            &pts,
            Sense::None,
            &Params::default(),
        );
        assert_eq!(o.case, Case::Forced);
        assert!(!hits(&o.velocity), "{:?}", o.velocity);
        // Without the look-ahead the literal slide runs into the wall.
        let literal = Params {
            forced_lookahead: false,
            ..Params::default()
        };
        let o = avoid(&x, &Vec2::new(10.0, -2.0), &pts, Sense::None, &literal);
        assert!(hits(&o.velocity), "{:?}", o.velocity);
    }

    #[test]
    fn close_wall_between_samples_still_triggers() {
        // Robot 3 units from a wall, heading straight between two samples
        // spaced 2 apart: the 0.1 rad cone alone would miss both
        // (atan(1/3) ≈ 0.32 rad); the corridor test must catch it.
        let p = Params::default();
        let wall: Vec<Vec2> = (-20..=20)
            .map(|k| Vec2::new(3.0, 2.0 * k as f64 + 1.0))
            .collect();
        let o = avoid(
            &Vec2::new(0.0, 0.0),
            &Vec2::new(10.0, 0.0),
            &wall,
            Sense::None,
            &p,
        );
        assert_ne!(o.case, Case::Free);
        let cone_only = Params {
            corridor_half_width: 0.0,
            ..Params::default()
        };
        let o = avoid(
            &Vec2::new(0.0, 0.0),
            &Vec2::new(10.0, 0.0),
            &wall,
            Sense::None,
            &cone_only,
        );
        assert_eq!(o.case, Case::Free);
    }

    // U: outer [440,560]×[450,535], walls 15 thick, cavity [455,545]×[450,520].
    fn trap() -> Vec<Vec2> {
        u_shape(440.0, 450.0, 120.0, 85.0, 15.0)
    }

    #[test]
    fn escapes_u_trap_without_entering_it() {
        let u = trap();
        for (start, goal) in [
            (Vec2::new(500.0, 330.0), Vec2::new(500.0, 700.0)),
            (Vec2::new(497.0, 300.0), Vec2::new(505.0, 700.0)),
            (Vec2::new(530.0, 320.0), Vec2::new(470.0, 680.0)),
        ] {
            let tr = run_to_goal(
                start,
                goal,
                std::slice::from_ref(&u),
                150,
                100.0,
                bsoa_runner(Params::default()),
            );
            assert_eq!(tr.crossed, None, "crossed the obstacle from {start:?}");
            assert!(
                !tr.path
                    .iter()
                    .any(|x| in_box(x, 455.0, 450.0, 545.0, 520.0)),
                "entered the cavity from {start:?}"
            );
            let t = tr
                .reached
                .unwrap_or_else(|| panic!("no goal from {start:?}: {:?}", tr.path.last()));
            // straight-line distance ≈ 37 steps; allow a detour
            assert!(t < 70, "took {t} steps from {start:?}");
        }
    }

    #[test]
    fn u_fixture_is_a_real_trap_without_avoidance() {
        let tr = run_to_goal(
            Vec2::new(500.0, 330.0),
            Vec2::new(500.0, 700.0),
            &[trap()],
            150,
            100.0,
            |_, v, _| *v,
        );
        assert!(tr.crossed.is_some());
        assert!(tr
            .path
            .iter()
            .any(|x| in_box(x, 455.0, 450.0, 545.0, 520.0)));
    }

    #[test]
    fn escapes_from_inside_the_u() {
        let u = trap();
        let tr = run_to_goal(
            Vec2::new(500.0, 480.0),
            Vec2::new(500.0, 700.0),
            &[u],
            200,
            100.0,
            bsoa_runner(Params::default()),
        );
        assert_eq!(tr.crossed, None);
        assert!(tr.reached.is_some(), "stuck at {:?}", tr.path.last());
    }

    #[test]
    fn passes_convex_box_and_gap() {
        let boxes = vec![rect(470.0, 450.0, 530.0, 480.0)];
        let tr = run_to_goal(
            Vec2::new(500.0, 350.0),
            Vec2::new(500.0, 600.0),
            &boxes,
            100,
            100.0,
            bsoa_runner(Params::default()),
        );
        assert_eq!(tr.crossed, None);
        assert!(tr.reached.unwrap() < 35);
        // two blocks with a 12-unit opening right on the straight line
        let blocks = vec![
            rect(420.0, 450.0, 494.0, 470.0),
            rect(506.0, 450.0, 580.0, 470.0),
        ];
        let tr = run_to_goal(
            Vec2::new(480.0, 350.0),
            Vec2::new(510.0, 600.0),
            &blocks,
            100,
            100.0,
            bsoa_runner(Params::default()),
        );
        assert_eq!(tr.crossed, None);
        assert!(tr.reached.unwrap() < 35);
    }

    #[test]
    fn the_order_of_the_obstacle_points_does_not_matter() {
        // The Sense frame gives the points as a set: any order must give the same step (but for
        // exact ties of the two nearest, which the generic positions below avoid).
        let p = Params::default();
        let mut pts = sample_boundary(&u_shape(40.0, -30.0, 60.0, 60.0, 4.0), 2.0);
        pts.extend(sample_boundary(&rect(-50.0, 30.0, -20.0, 34.0), 2.0));
        let mut reordered = pts.clone();
        reordered.reverse();
        reordered.rotate_left(17);
        let mut cases = std::collections::BTreeSet::new();
        for i in 0..400 {
            let a = i as f64 * 0.37 + 0.0123;
            let x = Vec2::new(30.0 * (a * 0.7).cos(), 25.0 * (a * 1.3).sin());
            let v_if = Vec2::new(a.cos(), a.sin()) * 10.0;
            for prev in [Sense::None, Sense::Clockwise, Sense::CounterClockwise] {
                let o = avoid(&x, &v_if, &pts, prev, &p);
                let r = avoid(&x, &v_if, &reordered, prev, &p);
                assert_eq!(format!("{o:?}"), format!("{r:?}"), "x {x:?} v_if {v_if:?}");
                cases.insert(format!("{:?}", o.case));
            }
        }
        // Every case of Table 2 was among them.
        assert!(cases.len() >= 4, "{cases:?}");
    }
}
