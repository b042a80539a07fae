//! Going to a point: a velocity for holonomic robots, (v, w) through the hunt kernels'
//! potential-field mapping (eqs. 2.11-2.16, `hunt::apf`) for unicycles; robots the robot
//! senses nearby repel it (2.13)-(2.15). And the capture ring's points.

use std::f64::consts::TAU;

use swarm::geometry::Vec2;
use swarm::scenario::{Kinematics, Scenario};
use swarm::Sense;

use super::params::BehaviourParams;
use crate::hunt::{apf, HuntParams};

/// Point `rank` of `n` evenly spaced on the circle of radius `r` around `centre`, the first due
/// east (the world frame: every member computes the same ring from the same member list).
pub fn ring_point(centre: [f64; 2], r: f64, rank: usize, n: usize) -> [f64; 2] {
    let a = TAU * rank as f64 / n.max(1) as f64;
    [centre[0] + r * a.cos(), centre[1] + r * a.sin()]
}

pub struct Mover {
    kinematics: Kinematics,
    v_max: f64,
    gain: f64,
    apf: HuntParams,
    /// In a hunt world: this robot's speed (km/min), turn rate (rad/min) and the minutes a
    /// tick (`[hunt]` rows and params), as the hunt behaviour drives its unicycles.
    hunt: Option<(f64, f64, f64)>,
}

impl Mover {
    pub fn new(sc: &Scenario, robot: u32, p: &BehaviourParams) -> Self {
        let hunt = sc.hunt().robots.get(robot as usize).map(|r| {
            (r.speed, r.turn_rate, sc.hunt().params.minutes_per_tick)
        });
        Self {
            kinematics: sc.robot.kinematics,
            v_max: sc.robot.v_max,
            gain: p.goto_gain,
            apf: if hunt.is_some() {
                sc.hunt().params.clone()
            } else {
                HuntParams::default()
            },
            hunt,
        }
    }

    pub fn stop(&self) -> [f64; 2] {
        [0.0, 0.0]
    }

    /// The command towards `goal` from the robot's pose in `s`.
    pub fn go(&self, s: &Sense, goal: [f64; 2]) -> [f64; 2] {
        let x = Vec2::new(s.pos[0], s.pos[1]);
        let g = Vec2::new(goal[0], goal[1]);
        match self.kinematics {
            Kinematics::Holonomic => {
                let d = g - x;
                let n = d.norm();
                if n <= 1e-12 {
                    return [0.0, 0.0];
                }
                let v = (self.gain * n).min(self.v_max);
                [d.x / n * v, d.y / n * v]
            }
            Kinematics::Unicycle { w_max } => {
                let others: Vec<Vec2> = s
                    .nearby()
                    .iter()
                    .map(|q| Vec2::new(q.pos[0], q.pos[1]))
                    .collect();
                let f = apf::total_force(&x, &g, &others, &self.apf);
                match self.hunt {
                    Some((v, w, dt)) => {
                        let c = apf::to_command(&f, s.heading, v, w, dt, &self.apf);
                        // km/min and rad/min to the world's per-tick units.
                        [c.v.max(0.0) * dt, c.w * dt]
                    }
                    None => {
                        let c = apf::to_command(&f, s.heading, self.v_max, w_max, 1.0, &self.apf);
                        [c.v, c.w]
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_points_are_evenly_spaced() {
        let p = ring_point([1.0, 2.0], 0.5, 1, 4);
        assert!((p[0] - 1.0).abs() < 1e-12 && (p[1] - 2.5).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn holonomic_go_is_capped_at_v_max_and_slows_near_the_goal() {
        let mut sc = Scenario::default();
        sc.robot.v_max = 0.05;
        let m = Mover::new(&sc, 0, &BehaviourParams::default());
        let s = Sense::zeroed();
        let c = m.go(&s, [3.0, 4.0]);
        assert!(((c[0] * c[0] + c[1] * c[1]).sqrt() - 0.05).abs() < 1e-12);
        let c = m.go(&s, [0.03, 0.04]);
        assert!(((c[0] * c[0] + c[1] * c[1]).sqrt() - 0.025).abs() < 1e-12);
    }
}
