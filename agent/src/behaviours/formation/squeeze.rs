//! Squeezing past wrecks (not in the paper, which has no dead robots): a robot that ORCA holds
//! still beside a wreck, away from its slot, for `squeeze_after_ticks` ticks stops keeping
//! ORCA's margin against the wrecks until it is clear of every one of them again (by that margin
//! and 1.5 steps).
//!
//! Why: ORCA grows every disc by `orca_margin` (0.05), so two wrecks 4.0-4.2 apart (centres)
//! leave a gap a robot fits through at the true radii (2 r = 2 from each) but not at ORCA's
//! 2 (r + margin) = 2.1. Robots were measured boxed in by such gaps for good (100 robots, 14
//! ids killed at once; the fixed C with five kills: exits of 4.14-4.17, docs/formation.md 9).
//! While squeezing, the wrecks stay in the robot's buffered cell at the true radii (a step
//! never overlaps them, cell_slack kept), and only their ORCA half-planes go; so do the
//! arena's discs' (static too; a robot wedged between a wreck and a disc with 0.05 to spare
//! at the true radii was measured still for good with the disc's margin). Robots keep their
//! margins. A run in which no robot is held beside a wreck is unchanged.

use swarm::geometry::Vec2;

/// A robot moving slower than this fraction of V_p is held still. [chosen] 1e-3: the boxed-in
/// robots of the measured runs had exactly 0; robots easing into their slots move at
/// V_p d / K_a, far above it until within epsilon.
pub const HELD_SPEED: f64 = 1e-3;

/// The squeeze state of one robot.
#[derive(Debug, Clone, Default)]
pub struct Squeeze {
    /// Consecutive ticks held still beside a wreck, away from the slot.
    held: u32,
    /// Squeezing: the wrecks keep only their buffered-cell half-planes.
    on: bool,
}

/// What one tick of motion saw, for [`Squeeze::update`].
pub struct Seen {
    /// The selected speed, units per second.
    pub speed: f64,
    /// V_p.
    pub max_speed: f64,
    /// Distance to the robot's slot (None: no slot).
    pub to_slot: Option<f64>,
    /// epsilon.
    pub epsilon: f64,
    /// Distance to the nearest wreck ORCA sees (infinite: none).
    pub nearest_wreck: f64,
    /// 2 (r + orca_margin): ORCA's contact distance with a wreck.
    pub contact: f64,
    /// One step at V_p.
    pub reach: f64,
}

impl Squeeze {
    /// Whether the wrecks lose their ORCA half-planes this tick.
    pub fn on(&self) -> bool {
        self.on
    }

    /// After a tick's motion. `after` = `squeeze_after_ticks` (0: never).
    pub fn update(&mut self, seen: &Seen, after: u32) {
        if after == 0 {
            return;
        }
        let beside = seen.nearest_wreck < seen.contact + 1.5 * seen.reach;
        if self.on {
            // Out of the zone it was held in (clear of every wreck by ORCA's margin and 1.5
            // steps): back to ORCA.
            if !beside {
                *self = Squeeze::default();
            }
            return;
        }
        let away = seen.to_slot.is_some_and(|d| d > seen.epsilon);
        if away && beside && seen.speed <= HELD_SPEED * seen.max_speed {
            self.held += 1;
            self.on = self.held >= after;
        } else {
            self.held = 0;
        }
    }
}

/// The wrecks a squeezing robot steers by: within `complete` (the distance to which its
/// Sense frame lists every wreck) the sensed ones, exact, and beyond it the remembered ones.
/// Remembered positions inside that radius are dropped: a robot's last place in `nearby`
/// (its ghost) lies a step from where it died, and a wreck heard in a message is rounded,
/// and either, beside the true wreck, was measured as a second disc closing the gap the robot
/// was squeezing through (100 robots, fixed C, five kills: a ghost 0.22 from the wreck).
pub fn trusted_wrecks(me: Vec2, remembered: &[Vec2], sensed: &[Vec2], complete: f64) -> Vec<Vec2> {
    let mut out: Vec<Vec2> = sensed.to_vec();
    out.extend(remembered.iter().filter(|w| (*w - me).norm() > complete).copied());
    out
}

/// How far a Sense frame lists every wreck: its sensing radius, or when the list is full (it
/// holds the nearest points only) the distance to its farthest point.
pub fn complete_radius(me: Vec2, listed: &[[f64; 2]], full: bool, sensing_radius: f64) -> f64 {
    if !full {
        return sensing_radius;
    }
    listed
        .iter()
        .map(|q| (Vec2::new(q[0], q[1]) - me).norm())
        .fold(0.0, f64::max)
        .min(sensing_radius)
}

/// The distance from `me` to the nearest of `wrecks` (infinite: none).
pub fn nearest(me: Vec2, wrecks: &[Vec2]) -> f64 {
    wrecks
        .iter()
        .map(|w| (w - me).norm())
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(speed: f64, to_slot: f64, nearest_wreck: f64) -> Seen {
        Seen {
            speed,
            max_speed: 1.0,
            to_slot: Some(to_slot),
            epsilon: 0.05,
            nearest_wreck,
            contact: 2.1,
            reach: 0.25,
        }
    }

    #[test]
    fn held_beside_a_wreck_it_squeezes_after_the_ticks_and_stops_once_clear() {
        let mut s = Squeeze::default();
        for _ in 0..9 {
            s.update(&seen(0.0, 4.0, 2.05), 10);
            assert!(!s.on());
        }
        s.update(&seen(0.0, 4.0, 2.05), 10);
        assert!(s.on());
        // Still beside a wreck while it passes.
        s.update(&seen(0.8, 3.0, 2.02), 10);
        assert!(s.on());
        s.update(&seen(0.8, 2.8, 2.3), 10);
        assert!(s.on());
        s.update(&seen(0.8, 2.5, 2.5), 10);
        assert!(!s.on());
    }

    #[test]
    fn a_squeezing_robot_trusts_its_sensor_within_the_listed_radius() {
        let me = Vec2::new(0.0, 0.0);
        let wreck = Vec2::new(2.05, 0.0);
        let ghost = Vec2::new(1.9, 0.2);
        let far = Vec2::new(9.0, 0.0);
        let w = trusted_wrecks(me, &[ghost, wreck, far], &[wreck], 5.0);
        assert_eq!(w, vec![wreck, far]);
        // A full list of points no farther than 3: only what lies within 3 is complete.
        let listed = [[1.0, 0.0], [0.0, 3.0]];
        assert_eq!(complete_radius(me, &listed, true, 5.0), 3.0);
        assert_eq!(complete_radius(me, &listed, false, 5.0), 5.0);
        let w = trusted_wrecks(me, &[Vec2::new(4.0, 0.0)], &[], 3.0);
        assert_eq!(w, vec![Vec2::new(4.0, 0.0)]);
    }

    #[test]
    fn moving_far_from_wrecks_or_in_place_never_squeezes() {
        let mut s = Squeeze::default();
        for _ in 0..50 {
            // Held, but no wreck near: a crowd of live robots.
            s.update(&seen(0.0, 4.0, 8.0), 10);
        }
        assert!(!s.on());
        for _ in 0..50 {
            // Beside a wreck, on its slot.
            s.update(&seen(0.0, 0.01, 2.3), 10);
        }
        assert!(!s.on());
        // A tick of motion resets the count.
        for k in 0..50 {
            let speed = if k % 5 == 4 { 0.5 } else { 0.0 };
            s.update(&seen(speed, 4.0, 2.05), 10);
        }
        assert!(!s.on());
        for _ in 0..50 {
            s.update(&seen(0.0, 4.0, 2.05), 0);
        }
        assert!(!s.on(), "0 turns it off");
    }
}
