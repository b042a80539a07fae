//! Reynolds flocking over the radio: every robot broadcasts its position and velocity each
//! tick; from what it heard it steers towards its neighbours' centre (cohesion), along their
//! mean velocity (alignment) and away from those too close (separation), and away from the
//! obstacle and wall points it senses.
//!
//! The message is the Python example's (examples/python-boids/boids.py): four little-endian
//! f64, `x, y, vx, vy` (32 bytes), carried as `Msg = Vec<u8>`. So Rust and Python boids hear
//! each other in a mixed swarm; anything else heard (another length) is ignored.

use rand::Rng;
use serde::Deserialize;
use swarm::agent::Agent;
use swarm::scenario::{ConfigError, Kinematics};
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The weights, from the `[agents.params]` table of the robot's `[[agents]]` entry.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Pull towards the centre of the neighbours heard (per tick, per unit of distance).
    pub cohesion: f64,
    /// Pull towards the neighbours' mean velocity.
    pub alignment: f64,
    /// Push away from neighbours closer than `separation_radius` (per 1/distance).
    pub separation: f64,
    /// Distance below which neighbours push apart.
    pub separation_radius: f64,
    /// Push away from sensed obstacle and wall points closer than `separation_radius`.
    pub avoid: f64,
    /// Cruising speed, as a fraction of robot.v_max: the speed a boid keeps when nothing acts.
    pub cruise: f64,
}

/// Why a boid cannot start.
#[derive(Debug)]
pub enum BoidsError {
    Params(ConfigError),
    Bad(String),
}

impl std::fmt::Display for BoidsError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            BoidsError::Params(e) => write!(f, "{e}"),
            BoidsError::Bad(s) => f.write_str(s),
        }
    }
}

impl From<ConfigError> for BoidsError {
    fn from(e: ConfigError) -> BoidsError {
        BoidsError::Params(e)
    }
}

/// Bytes of the boid message: four f64 (`x, y, vx, vy`), little-endian, as Python's
/// `struct "<4d"`.
pub const BOID_MSG_BYTES: usize = 32;

/// A neighbour as heard this tick: its position and velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heard {
    pub pos: [f64; 2],
    pub vel: [f64; 2],
}

/// The boid message's bytes: `x, y, vx, vy` as little-endian f64.
pub fn encode(h: Heard) -> Vec<u8> {
    [h.pos[0], h.pos[1], h.vel[0], h.vel[1]]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// A boid message, or `None` when the bytes are not one (another robot program's message).
pub fn decode(bytes: &[u8]) -> Option<Heard> {
    if bytes.len() != BOID_MSG_BYTES {
        return None;
    }
    let f = |i: usize| f64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap());
    let h = Heard {
        pos: [f(0), f(1)],
        vel: [f(2), f(3)],
    };
    [h.pos[0], h.pos[1], h.vel[0], h.vel[1]]
        .iter()
        .all(|v| v.is_finite())
        .then_some(h)
}

pub struct Boids {
    p: Params,
    v_max: f64,
    /// The velocity kept when no force acts (a random start heading at cruise speed).
    cruise_vel: [f64; 2],
}

impl Boids {
    pub fn new(p: Params, a: &Agent) -> Result<Boids, BoidsError> {
        let sc = a.scenario();
        if sc.robot.kinematics != Kinematics::Holonomic {
            return Err(BoidsError::Bad(
                "boids command velocities: robot.kinematics must be holonomic".into(),
            ));
        }
        for (name, v) in [
            ("cohesion", p.cohesion),
            ("alignment", p.alignment),
            ("separation", p.separation),
            ("separation_radius", p.separation_radius),
            ("avoid", p.avoid),
            ("cruise", p.cruise),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(BoidsError::Bad(format!(
                    "params.{name} = {v}: allowed a number >= 0"
                )));
            }
        }
        if p.cruise > 1.0 {
            return Err(BoidsError::Bad(format!(
                "params.cruise = {}: allowed 0..=1 (a fraction of robot.v_max)",
                p.cruise
            )));
        }
        // The run's seeded stream of this robot: the same heading in every run of the seed.
        let heading: f64 = a
            .rng(0)
            .gen_range(-std::f64::consts::PI..std::f64::consts::PI);
        let v_max = sc.robot.v_max;
        let s = p.cruise * v_max;
        Ok(Boids {
            cruise_vel: [s * heading.cos(), s * heading.sin()],
            v_max,
            p,
        })
    }
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn norm(a: [f64; 2]) -> f64 {
    (a[0] * a[0] + a[1] * a[1]).sqrt()
}

impl Behaviour for Boids {
    type Msg = Vec<u8>;

    fn step_refs(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<Vec<u8>>],
        out: &mut Outbox<Vec<u8>>,
    ) -> Command {
        let me = sense.pos;
        // Neighbours: the boids heard this tick (the radio's range decides who they are).
        let now: Vec<Heard> = inbox.iter().filter_map(|r| decode(&r.msg)).collect();
        let mut v = self.cruise_vel;
        if !now.is_empty() {
            let n = now.len() as f64;
            let centre = now
                .iter()
                .fold([0.0, 0.0], |c, h| [c[0] + h.pos[0], c[1] + h.pos[1]]);
            let to_centre = sub([centre[0] / n, centre[1] / n], me);
            let s = now
                .iter()
                .fold([0.0, 0.0], |c, h| [c[0] + h.vel[0], c[1] + h.vel[1]]);
            let mean_vel = [s[0] / n, s[1] / n];
            let align = sub(mean_vel, sense.vel);
            v[0] = sense.vel[0] + self.p.cohesion * to_centre[0] + self.p.alignment * align[0];
            v[1] = sense.vel[1] + self.p.cohesion * to_centre[1] + self.p.alignment * align[1];
            for h in &now {
                let away = sub(me, h.pos);
                let d = norm(away);
                if d > 1e-9 && d < self.p.separation_radius {
                    v[0] += self.p.separation * away[0] / (d * d);
                    v[1] += self.p.separation * away[1] / (d * d);
                }
            }
        }
        let points = &sense.obstacle_points[..sense.n_obstacle_points as usize];
        for &q in points {
            let away = sub(me, q);
            let d = norm(away);
            if d > 1e-9 && d < self.p.separation_radius {
                v[0] += self.p.avoid * away[0] / (d * d);
                v[1] += self.p.avoid * away[1] / (d * d);
            }
        }
        // Keep moving: below cruise speed, speed up along the current direction.
        let s = norm(v);
        let cruise = self.p.cruise * self.v_max;
        if s < cruise && s > 1e-9 {
            v = [v[0] * cruise / s, v[1] * cruise / s];
        } else if s > self.v_max {
            v = [v[0] * self.v_max / s, v[1] * self.v_max / s];
        }
        if s > 1e-9 {
            self.cruise_vel = [v[0] * cruise / norm(v), v[1] * cruise / norm(v)];
        }
        out.broadcast(encode(Heard {
            pos: me,
            vel: sense.vel,
        }));
        Command {
            cmd: v,
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_is_pythons_struct_4d() {
        let h = Heard {
            pos: [1.5, -2.0],
            vel: [0.25, 3.0],
        };
        let b = encode(h);
        assert_eq!(b.len(), BOID_MSG_BYTES);
        // Python: struct.pack("<4d", 1.5, -2.0, 0.25, 3.0)[:8] == 1.5 as LE f64.
        assert_eq!(&b[..8], &1.5f64.to_le_bytes());
        assert_eq!(decode(&b), Some(h));
        assert_eq!(decode(&b[..31]), None);
        let mut nan = b.clone();
        nan[..8].copy_from_slice(&f64::NAN.to_le_bytes());
        assert_eq!(decode(&nan), None);
    }
}
