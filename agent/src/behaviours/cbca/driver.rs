//! Test-only synchronous world for the CBCA behaviour: robots step in id order on one tick's
//! Sense frames, messages sent at tick k arrive at k + 1 if the sender was within
//! `radio.comm_radius` at k and a seeded loss draw keeps them; holonomic motion; targets stand
//! still and are captured when L_j robots are within `capture_radius` of them (the hunt
//! mission's rule is the world's; this stands in for it). Robots can be killed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use swarm::frames::{Entity, ENTITY_HAS_POS, MAX_ENTITIES};
use swarm::scenario::Scenario;
use swarm::{Behaviour, Outbox, Received, Sense};

use super::messages::{encoded_bytes, CbcaRadio};
use super::robot::Cbca;
use super::{Section, TARGET_SENSING};

pub struct Target {
    pub pos: [f64; 2],
    pub needed: usize,
    pub captured_at: Option<u64>,
}

pub struct Driver {
    pub sc: Scenario,
    pub robots: Vec<Cbca>,
    pub pos: Vec<[f64; 2]>,
    pub alive: Vec<bool>,
    /// Radio links cut (from, to), 0-based: a robot whose radio fails towards some peers.
    pub muted: std::collections::BTreeSet<(usize, usize)>,
    /// Robots that do not move (stuck): their commands are ignored.
    pub frozen: Vec<bool>,
    pub targets: Vec<Target>,
    pub loss: f64,
    pub capture_radius: f64,
    rng: ChaCha8Rng,
    in_flight: Vec<(u32, [f64; 2], CbcaRadio)>,
    pub tick: u64,
    pub sent: u64,
    pub bytes: u64,
    seq: u32,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// A scenario holding the `[cbca]` section of an example file, scaled for the behaviour: km,
/// 0.05 km a tick, the thesis's 1.5 km radio.
pub fn scenario(example: u32) -> Scenario {
    let path = format!(
        "{}/../configs/hunt-cbca-example{example}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let file: toml::Table = std::fs::read_to_string(path).unwrap().parse().unwrap();
    let mut sc = Scenario::default();
    sc.run.behaviour = "cbca".into();
    *sc.cbca_mut() = file["cbca"].as_table().unwrap().clone();
    sc.run.robots = sc.cbca()["robots"].as_array().unwrap().len() as u32;
    sc.arena.width = 10.0;
    sc.arena.height = 10.0;
    sc.arena.start_region = [0.0, 0.0, 10.0, 10.0];
    sc.robot.v_max = 0.05;
    sc.robot.sensing_radius = 1.2;
    sc.radio.comm_radius = 1.5;
    sc.robot.neighbour_sensing_radius = 1.5; // as configs/hunt-cbca.toml
    sc.radio.max_message_bytes = 8192;
    sc
}

impl Driver {
    pub fn new(sc: Scenario, loss: f64, seed: u64) -> Driver {
        let c = swarm::scenario::Check {
            key_source: &|k| k.to_string(),
        };
        crate::behaviours::validate_with(&sc, &c).expect("valid scenario");
        let sec = Section::of(&sc, &c).unwrap();
        let rows = sec.kernels.robots().unwrap();
        let tasks = sec.kernels.tasks().unwrap();
        let n = rows.len();
        Driver {
            robots: (0..n as u32).map(|i| Cbca::new(&sec, &sc, i)).collect(),
            pos: rows.iter().map(|r| [r.position.x, r.position.y]).collect(),
            alive: vec![true; n],
            muted: Default::default(),
            frozen: vec![false; n],
            targets: tasks
                .iter()
                .map(|t| Target {
                    pos: t.position,
                    needed: t.robots_needed,
                    captured_at: None,
                })
                .collect(),
            loss,
            capture_radius: sec.behaviour.ring_radius_km + 0.05,
            rng: ChaCha8Rng::seed_from_u64(seed),
            in_flight: Vec::new(),
            tick: 0,
            sent: 0,
            bytes: 0,
            seq: 0,
            sc,
        }
    }

    fn sense(&self, i: usize) -> Box<Sense> {
        let mut s = Sense::zeroed();
        s.tick = self.tick;
        s.robot = i as u32;
        s.pos = self.pos[i];
        // The proximity sensor (Sense `nearby`), as the world fills it.
        let reach = self.sc.robot.neighbour_sensing_radius;
        let mut k = 0;
        for j in 0..self.pos.len() {
            if j != i && self.alive[j] && dist(self.pos[i], self.pos[j]) <= reach && k < swarm::frames::MAX_NEARBY {
                s.nearby[k] = swarm::frames::Nearby {
                    robot: j as u32,
                    reserved: 0,
                    pos: self.pos[j],
                    vel: [0.0, 0.0],
                };
                k += 1;
            }
        }
        s.n_nearby = k as u32;
        let mut e = 0;
        for (id, t) in self.targets.iter().enumerate().take(MAX_ENTITIES) {
            if dist(self.pos[i], t.pos) <= self.sc.robot.sensing_radius {
                let mut flags = ENTITY_HAS_POS;
                if t.captured_at.is_some() {
                    flags |= TARGET_SENSING.captured_flag;
                }
                s.entities[e] = Entity {
                    id: id as u32 + 1,
                    kind: TARGET_SENSING.kind,
                    flags,
                    reserved: 0,
                    pos: t.pos,
                    value: 0.0,
                };
                e += 1;
            }
        }
        s.n_entities = e as u32;
        s
    }

    /// One tick for every live robot.
    // Robot i's Sense, inbox and move are three arrays indexed alike.
    #[allow(clippy::needless_range_loop)]
    pub fn step(&mut self) {
        let sent = std::mem::take(&mut self.in_flight);
        let mut next = Vec::new();
        let mut moves = vec![[0.0; 2]; self.pos.len()];
        for i in 0..self.robots.len() {
            if !self.alive[i] {
                continue;
            }
            let s = self.sense(i);
            let mut inbox = Vec::new();
            for (from, at, m) in &sent {
                if *from as usize == i
                    || dist(*at, self.pos[i]) > self.sc.radio.comm_radius
                    || self.muted.contains(&(*from as usize, i))
                {
                    continue;
                }
                if self.loss > 0.0 && self.rng.gen::<f64>() < self.loss {
                    continue;
                }
                inbox.push(Received {
                    from: *from,
                    tick: self.tick.saturating_sub(1),
                    seq: 0,
                    sender_pos: *at,
                    unicast: false,
                    msg: m.clone(),
                });
            }
            let mut out = Outbox::new_for_tests(8);
            let c = self.robots[i].step(&s, &inbox, &mut out);
            moves[i] = c.cmd;
            for (_, m) in out.queued() {
                self.sent += 1;
                self.bytes += encoded_bytes(m) as u64;
                self.seq += 1;
                next.push((i as u32, self.pos[i], m.clone()));
            }
        }
        for (i, m) in moves.iter().enumerate() {
            if self.frozen[i] {
                continue;
            }
            self.pos[i][0] += m[0];
            self.pos[i][1] += m[1];
        }
        for t in &mut self.targets {
            let near = (0..self.pos.len())
                .filter(|&i| self.alive[i] && dist(self.pos[i], t.pos) <= self.capture_radius)
                .count();
            if t.captured_at.is_none() && near >= t.needed {
                t.captured_at = Some(self.tick);
            }
        }
        self.in_flight = next;
        self.tick += 1;
    }

    pub fn run_until(&mut self, max_ticks: u64, done: impl Fn(&Driver) -> bool) -> bool {
        while self.tick < max_ticks {
            if done(self) {
                return true;
            }
            self.step();
        }
        done(self)
    }

    pub fn all_committed(&self) -> bool {
        self.robots
            .iter()
            .zip(&self.alive)
            .all(|(r, &a)| !a || r.phase() == super::robot::Phase::Executing)
    }

    /// Every target captured, and every live robot's path empty (its holds over).
    pub fn all_finished(&self) -> bool {
        self.targets.iter().all(|t| t.captured_at.is_some())
            && self
                .robots
                .iter()
                .zip(&self.alive)
                .all(|(r, &a)| !a || r.path().is_empty())
    }

    /// The communication components of the live robots now (comm_radius), 0-based.
    pub fn components(&self) -> Vec<Vec<usize>> {
        let r = self.sc.radio.comm_radius;
        let graph: Vec<Vec<usize>> = (0..self.pos.len())
            .map(|i| {
                (0..self.pos.len())
                    .filter(|&j| {
                        j != i && self.alive[i] && self.alive[j] && dist(self.pos[i], self.pos[j]) <= r
                    })
                    .collect()
            })
            .collect();
        crate::cbca::grouping::components(&graph)
            .into_iter()
            .filter(|g| self.alive[g[0]])
            .collect()
    }

    /// Kills robot i (its process dies: it stops sending, the proximity sensors lose it).
    pub fn kill(&mut self, i: usize) {
        self.alive[i] = false;
        self.in_flight.retain(|(from, _, _)| *from as usize != i);
    }

    /// Each task's winners as robot `i` believes them (1-based labels for messages).
    pub fn coalitions(&self, i: usize) -> Vec<Vec<usize>> {
        let w = self.robots[i].kernel().winners();
        (0..w.n_tasks())
            .map(|j| w.winners_of(j).into_iter().map(|(m, _)| m + 1).collect())
            .collect()
    }
}
