//! The search paper's mission (docs/search.md 1.1-1.4): targets, their placement, the signal of
//! eq. (33) each robot measures, and "found" (a robot closer than L_0; the target then stops
//! emitting). The run is complete when every target is found (`search.end_when_all_found`).

use crate::section::SearchScenario;
use crate::section::{ENTITY_SIGNAL, STATE_COOPERATIVE, STATE_DECLARED};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use swarm::frames::{Entity, Sense, ENTITY_DONE_BY_YOU};
use swarm::geometry::{point_in_polygon, polygon_distance, Vec2};
use swarm::radio::distance;
use swarm::recording::Event;
use swarm::scenario::{Check, ConfigError, Scenario};
use world::mission::{
    DisplayState, LegendEntry, Mark, Mission, MissionEntry, MissionError, RunFacts,
};

use crate::section::MAX_SIGNALS as MAX_SIGNALS_SENSED;

pub const ENTRY: MissionEntry = MissionEntry {
    name: "search",
    progress_label: "targets found",
    implied_by: &["search"],
    sections: &["search"],
    validate,
    new,
};

/// Checks the world's side of the `[search]` section (the behaviour checks mode and kernels).
fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let s = &sc.search();
    c.range_u("search.targets", s.targets as u64, 1, 1024)?;
    let [x0, y0, x1, y1] = s.target_region;
    let inside = [x0, y0, x1, y1].iter().all(|v| v.is_finite())
        && 0.0 <= x0
        && x0 < x1
        && x1 <= sc.arena.width
        && 0.0 <= y0
        && y0 < y1
        && y1 <= sc.arena.height;
    if !inside {
        return Err(c.err(
            "search.target_region",
            format!(
                "= {:?} must be [x0, y0, x1, y1] with 0 <= x0 < x1 <= arena.width = {} and 0 <= y0 < y1 <= arena.height = {}",
                s.target_region, sc.arena.width, sc.arena.height
            ),
        ));
    }
    c.range_f(
        "search.target_clearance",
        s.target_clearance,
        0.0,
        1e6,
        false,
    )?;
    c.range_f("search.signal_m", s.signal_m, 0.0, 1e12, true)?;
    c.range_f("search.signal_q", s.signal_q, 0.0, 1e12, true)?;
    c.range_f("search.noise_sigma", s.noise_sigma, 0.0, 1e12, false)?;
    c.range_f("search.l_t", s.l_t, 0.0, 1e7, true)?;
    c.range_f("search.found_distance", s.found_distance, 0.0, 1e7, true)?;
    // The placement the mission does at start, with the same seeded stream: a region with no
    // room clear of the obstacles is refused now, naming the keys that decide it.
    Targets::new(sc).map_err(|e| {
        let MissionError::Setup { message, .. } = e;
        c.err(
            "search.target_region",
            format!(
                "= {:?}: {message}: the region must leave room for search.targets = {} \
                 outside the obstacles and search.target_clearance = {} from them",
                s.target_region, s.targets, s.target_clearance
            ),
        )
    })?;
    Ok(())
}

fn new(sc: &Scenario) -> Result<Box<dyn Mission>, MissionError> {
    Ok(Box::new(SearchMission {
        targets: Targets::new(sc)?,
        sc: sc.clone(),
    }))
}

/// A sensed signal of target `t`.
fn signal(t: u32, flags: u32, intensity: f64) -> Entity {
    Entity {
        id: t,
        kind: ENTITY_SIGNAL,
        flags,
        reserved: 0,
        pos: [0.0; 2],
        value: intensity,
    }
}

/// The search scenario's measures (docs/search.md 4.3 and 5 item 30).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SearchMetrics {
    pub targets: u32,
    pub found: u32,
    /// Iteration steps until the last target was found (tick of that find + 1); None when the
    /// run ended first (censored at max_ticks).
    pub steps: Option<u64>,
    /// Total energy: sum over robots and ticks of the distance moved (P_th = sum ||V_i(t)||).
    pub energy: f64,
    /// Per target: (tick found, robot), or None.
    pub found_at: Vec<Option<(u64, u32)>>,
}

pub struct SearchMission {
    sc: Scenario,
    pub targets: Targets,
}

/// Trajectory colours by state, as the paper's Fig. 6: roaming blue, cooperative orange,
/// declared green.
const STATES: &[DisplayState] = &[
    DisplayState {
        state: 0,
        name: "roaming",
        colour: [60, 90, 200],
    },
    DisplayState {
        state: STATE_COOPERATIVE as u8,
        name: "cooperative",
        colour: [230, 120, 0],
    },
    DisplayState {
        state: STATE_DECLARED as u8,
        name: "declared",
        colour: [0, 150, 60],
    },
];

const GREEN: [u8; 3] = [0, 255, 0];
const RED: [u8; 3] = [255, 0, 0];
const BLACK: [u8; 3] = [0, 0, 0];

fn found_mark(at: [f64; 2]) -> Mark {
    Mark::Disc {
        at,
        px: 7,
        fill: GREEN,
        outline: Some(BLACK),
    }
}

fn missed_mark(at: [f64; 2]) -> Mark {
    Mark::Ring {
        at,
        px: 7,
        colour: RED,
        width: 3,
    }
}

impl SearchMission {
    /// The search mission of `world`, if it runs one.
    pub fn of(world: &world::World) -> Option<&SearchMission> {
        world.mission.as_any().downcast_ref::<SearchMission>()
    }
}

impl Mission for SearchMission {
    fn name(&self) -> &'static str {
        "search"
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn sense(&mut self, robot: u32, pos: [f64; 2], out: &mut Sense) {
        self.targets.sense(&self.sc, robot, pos, out);
    }
    fn update(&mut self, tick: u64, poses: &[[f64; 3]], alive: &[bool], events: &mut Vec<Event>) {
        for (robot, target) in self.targets.update(&self.sc, tick, poses, alive) {
            events.push(Event::EntityDone {
                entity: target,
                robot,
            });
        }
    }
    fn progress(&self) -> (u32, u32) {
        (self.targets.found_count(), self.targets.pos.len() as u32)
    }
    fn complete(&self) -> bool {
        self.sc.search().end_when_all_found && self.targets.all_found()
    }
    fn end_reason(&self) -> &'static str {
        "all targets found"
    }
    fn metrics(&self, facts: &RunFacts) -> Option<serde_json::Value> {
        let t = &self.targets;
        let m = SearchMetrics {
            targets: t.pos.len() as u32,
            found: t.found_count(),
            steps: if t.all_found() {
                t.found.iter().filter_map(|f| f.map(|x| x.0 + 1)).max()
            } else {
                None
            },
            energy: facts.distance_travelled,
            found_at: t.found.clone(),
        };
        serde_json::to_value(m).ok()
    }
    fn display_states(&self) -> &'static [DisplayState] {
        STATES
    }
    fn layer(&self) -> Vec<Mark> {
        let t = &self.targets;
        t.pos
            .iter()
            .zip(&t.found)
            .map(|(p, f)| {
                if f.is_some() {
                    found_mark(*p)
                } else {
                    missed_mark(*p)
                }
            })
            .collect()
    }
    fn legend(&self) -> Vec<LegendEntry> {
        vec![
            LegendEntry {
                mark: found_mark([0.0; 2]),
                label: "target found",
            },
            LegendEntry {
                mark: missed_mark([0.0; 2]),
                label: "target missed",
            },
        ]
    }
}

pub struct Targets {
    pub pos: Vec<[f64; 2]>,
    /// Tick at which each target was found, and by whom.
    pub found: Vec<Option<(u64, u32)>>,
    /// Signal noise: one N(0, sigma^2) draw per (tick, robot, target in range), in that order.
    noise: ChaCha8Rng,
    /// Robot -> target it found at the last apply (reported once in its next Sense).
    just_found: Vec<(u32, u32)>,
}

/// Standard normal draw (Box-Muller), from the seeded stream only.
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

impl Targets {
    pub fn new(sc: &Scenario) -> Result<Targets, MissionError> {
        let mut rng = swarm::streams::rng(
            sc.run.seed,
            swarm::streams::WORLD,
            swarm::streams::TARGET_PLACEMENT,
        );
        let [x0, y0, x1, y1] = sc.search().target_region;
        let mut pos = Vec::new();
        for t in 0..sc.search().targets {
            let mut ok = false;
            for _ in 0..100_000 {
                let p = Vec2::new(rng.gen_range(x0..x1), rng.gen_range(y0..y1));
                let clear = sc.arena.obstacles.iter().all(|o| {
                    !point_in_polygon(p, &o.points)
                        && polygon_distance(p, &o.points) >= sc.search().target_clearance
                });
                if clear {
                    pos.push([p.x, p.y]);
                    ok = true;
                    break;
                }
            }
            if !ok {
                return Err(MissionError::Setup {
                    key: "search.target_region".into(),
                    message: format!("no free position for target {t}"),
                });
            }
        }
        Ok(Targets {
            found: vec![None; pos.len()],
            pos,
            noise: swarm::streams::rng(
                sc.run.seed,
                swarm::streams::WORLD,
                swarm::streams::SIGNAL_NOISE,
            ),
            just_found: Vec::new(),
        })
    }

    pub fn found_count(&self) -> u32 {
        self.found.iter().filter(|f| f.is_some()).count() as u32
    }

    pub fn all_found(&self) -> bool {
        !self.pos.is_empty() && self.found.iter().all(|f| f.is_some())
    }

    /// Eq. (33): I = m Q / d^2 + eta for d <= L_T, else 0. Writes the robot's signal list
    /// (strongest first is left to the behaviour; listed in target order).
    pub fn sense(&mut self, sc: &Scenario, robot: u32, p: [f64; 2], out: &mut Sense) {
        let mut n = 0;
        for &(r, t) in &self.just_found {
            if r == robot && n < MAX_SIGNALS_SENSED {
                out.entities[n] = signal(t, ENTITY_DONE_BY_YOU, 0.0);
                n += 1;
            }
        }
        let s = &sc.search();
        for (t, q) in self.pos.iter().enumerate() {
            if self.found[t].is_some() {
                continue;
            }
            let d = distance(p, *q);
            if d > s.l_t || n >= MAX_SIGNALS_SENSED {
                continue;
            }
            let clean = s.signal_m * s.signal_q / (d * d).max(1e-9);
            let intensity = clean + s.noise_sigma * normal(&mut self.noise);
            out.entities[n] = signal(t as u32, 0, intensity);
            n += 1;
        }
        out.n_entities = n as u32;
    }

    /// After the moves of tick k: targets with a robot closer than L_0 are found (lowest robot
    /// id first when several arrive together). Returns (robot, target) pairs found now.
    pub fn update(
        &mut self,
        sc: &Scenario,
        tick: u64,
        poses: &[[f64; 3]],
        alive: &[bool],
    ) -> Vec<(u32, u32)> {
        self.just_found.clear();
        for t in 0..self.pos.len() {
            if self.found[t].is_some() {
                continue;
            }
            let finder = poses
                .iter()
                .enumerate()
                .filter(|(i, _)| alive[*i])
                .find(|(_, p)| distance([p[0], p[1]], self.pos[t]) < sc.search().found_distance)
                .map(|(i, _)| i as u32);
            if let Some(r) = finder {
                self.found[t] = Some((tick, r));
                self.just_found.push((r, t as u32));
            }
        }
        self.just_found.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(sc: &Scenario) -> Result<(), ConfigError> {
        validate(
            sc,
            &Check {
                key_source: &|_| "t.toml".to_string(),
            },
        )
    }

    fn key_of(edit: impl Fn(&mut Scenario)) -> String {
        let mut sc = Scenario::default();
        edit(&mut sc);
        check(&sc).expect_err("refused").key
    }

    #[test]
    fn the_default_section_is_valid() {
        check(&Scenario::default()).unwrap();
    }

    #[test]
    fn empty_inverted_or_outside_target_regions_are_refused() {
        for r in [
            [0.0, 0.0, 0.0, 0.0],
            [500.0, 500.0, 400.0, 600.0],
            [500.0, 600.0, 600.0, 500.0],
            [900.0, 900.0, 1100.0, 950.0],
            [-10.0, 0.0, 100.0, 100.0],
            [f64::NAN, 0.0, 100.0, 100.0],
            [0.0, 0.0, f64::INFINITY, 100.0],
        ] {
            assert_eq!(
                key_of(|sc| sc.search_mut().target_region = r),
                "search.target_region",
                "{r:?}"
            );
        }
    }

    #[test]
    fn values_that_make_the_mission_impossible_are_refused() {
        assert_eq!(key_of(|sc| sc.search_mut().targets = 0), "search.targets");
        for v in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
            assert_eq!(
                key_of(|sc| sc.search_mut().found_distance = v),
                "search.found_distance",
                "{v}"
            );
        }
        assert_eq!(
            key_of(|sc| sc.search_mut().target_clearance = -1.0),
            "search.target_clearance"
        );
        assert_eq!(
            key_of(|sc| sc.search_mut().signal_m = f64::NAN),
            "search.signal_m"
        );
        assert_eq!(key_of(|sc| sc.search_mut().l_t = -5.0), "search.l_t");
    }

    #[test]
    fn a_target_region_with_no_room_clear_of_obstacles_is_refused() {
        let mut sc = Scenario::default();
        sc.arena.obstacles.push(swarm::scenario::Obstacle {
            name: "slab".into(),
            points: vec![
                [400.0, 400.0],
                [600.0, 400.0],
                [600.0, 600.0],
                [400.0, 600.0],
            ],
        });
        // Inside the slab: no free point at all.
        sc.search_mut().target_region = [450.0, 450.0, 550.0, 550.0];
        let e = check(&sc).unwrap_err();
        assert_eq!(e.key, "search.target_region");
        assert!(e.to_string().contains("no free position"), "{e}");
        // A free strip beside it, but a clearance wider than the strip's distance to it.
        sc.search_mut().target_region = [600.5, 450.0, 601.0, 550.0];
        sc.search_mut().target_clearance = 5.0;
        assert_eq!(check(&sc).unwrap_err().key, "search.target_region");
        sc.search_mut().target_clearance = 0.1;
        check(&sc).unwrap();
        // What validation accepted, the mission sets up.
        Targets::new(&sc).unwrap();
    }
}
