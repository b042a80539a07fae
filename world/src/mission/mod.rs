//! Missions: what is particular to one paper's world, beside the mission-free core
//! (`world.rs`: physics, sensing of robots and obstacles, radio accounting, faults, recording).
//!
//! A mission owns its entities (targets, evaders, pattern slots), how they move, what robots
//! sense of them (Sense `entities`), when it is complete, its metrics for `summary.json`, its
//! layer of `run.svg` and its events in `recording.bin`. Adding one is adding its file and its
//! name in `missions!` below (which declares its module and lists its `ENTRY` in
//! [`MISSIONS`]); a mission with a scenario section of its own also gives the section's type
//! a field in `swarm::scenario::Scenario` (its file in `swarm/src/sections/`).

/// The evaders' escape strategy of the hunting thesis (eq. 2.17), for the hunt mission to come.
pub mod hunt_escape;

use serde::Serialize;
use swarm::frames::Sense;
use swarm::recording::Event;
use swarm::scenario::{Check, ConfigError, Scenario};

/// Why a mission could not be set up for a scenario that passed validation.
#[derive(Debug, thiserror::Error)]
pub enum MissionError {
    /// The scenario's key `key` admits no setup (e.g. no free place for a target).
    #[error("{key}: {message}")]
    Setup { key: String, message: String },
}

/// A display state as its mission names it: the state byte of an Action, and how pictures
/// colour a robot in it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DisplayState {
    pub state: u8,
    pub name: &'static str,
    pub colour: [u8; 3],
}

/// One mark of a mission's layer of a picture (its home is `swarm::layer`, so recordings
/// hold it too).
pub use swarm::layer::Mark;

/// A legend entry: how the mark looks and what it means.
#[derive(Debug, Clone, PartialEq)]
pub struct LegendEntry {
    pub mark: Mark,
    pub label: &'static str,
}

/// Facts of the run the core measured, for a mission's metrics.
#[derive(Debug, Clone, Copy)]
pub struct RunFacts {
    /// Ticks run.
    pub ticks: u64,
    /// Total distance the robots moved.
    pub distance_travelled: f64,
}

/// The world side of one paper's mission.
pub trait Mission: Send + Sync {
    /// The registry's name.
    fn name(&self) -> &'static str;
    /// Where the agents start, (x, y, heading) for each of `run.robots` (stations included),
    /// when the mission's scenario places them (the hunt's tables); None: the world draws
    /// them in `arena.start_region`.
    fn start_poses(&self, _sc: &Scenario) -> Option<Vec<[f64; 3]>> {
        None
    }
    /// Each agent's own limits, [speed, turn rate] in the world's units (per tick), for the
    /// `run.robots` agents, when the mission's scenario gives robots their own (the hunt's
    /// per-robot `speed` and `turn_rate`); the world rejects a command over the robot's own
    /// limits as over `robot.v_max`. None: every robot has `robot.v_max` and the kinematics'
    /// `w_max`.
    fn robot_limits(&self, _sc: &Scenario) -> Option<Vec<[f64; 2]>> {
        None
    }
    /// Writes what robot `robot` at `pos` senses of the mission's entities into
    /// `out.entities` (and `n_entities`, which the core sets to 0 before). Called for the live
    /// robots in id order each tick, so a mission may draw sensor noise from its own stream.
    fn sense(&mut self, robot: u32, pos: [f64; 2], out: &mut Sense);
    /// Robot `robot`'s report of this tick (Action `report`; accepted actions only, before the
    /// moves). Most missions ignore it.
    fn observe(&mut self, _robot: u32, _report: [f64; 4]) {}
    /// After the moves of tick `tick`: the entities move and the mission judges progress,
    /// pushing its events.
    fn update(&mut self, tick: u64, poses: &[[f64; 3]], alive: &[bool], events: &mut Vec<Event>);
    /// (done, total) of what the mission counts (search: targets found of targets; what it
    /// counts is its registry entry's `progress_label`).
    fn progress(&self) -> (u32, u32);
    /// The run ends now; `end_reason` says why.
    fn complete(&self) -> bool;
    /// How a run ended by `complete` is reported ("all targets found").
    fn end_reason(&self) -> &'static str;
    /// The mission's metrics for summary.json (under `mission.<name>`), None for none.
    fn metrics(&self, facts: &RunFacts) -> Option<serde_json::Value>;
    /// The mission itself, for tests and tools that know which one it is
    /// (`downcast_ref::<search::SearchMission>()`).
    fn as_any(&self) -> &dyn std::any::Any;
    /// The display states its behaviours use; empty: pictures colour robots by id.
    fn display_states(&self) -> &'static [DisplayState] {
        &[]
    }
    /// Its layer of run.svg (drawn over the trajectories, under the robots).
    fn layer(&self) -> Vec<Mark> {
        Vec::new()
    }
    /// Its layer as it stands now, for the viewer: written into a version-3 recording after
    /// every tick the layer changes (`swarm::recording::TickLayer`). The default is [`layer`];
    /// a mission whose `layer` grows with the run (a path of all its history) overrides it
    /// with what is true at this tick only (positions, states), so a tick costs the same all
    /// run long.
    ///
    /// [`layer`]: Mission::layer
    fn live_layer(&self) -> Vec<Mark> {
        self.layer()
    }
    /// Legend entries for its layer.
    fn legend(&self) -> Vec<LegendEntry> {
        Vec::new()
    }
}

/// A registry line: a mission's name, the behaviours that imply it when `run.mission` is left
/// out, the check of its scenario section, and its constructor.
#[derive(Clone, Copy)]
pub struct MissionEntry {
    pub name: &'static str,
    /// What its progress counts, for progress bars ("targets found"); empty: nothing.
    pub progress_label: &'static str,
    pub implied_by: &'static [&'static str],
    /// The scenario sections it reads (a run refuses any other behaviour's or mission's
    /// section).
    pub sections: &'static [&'static str],
    pub validate: fn(&Scenario, &Check) -> Result<(), ConfigError>,
    pub new: fn(&Scenario) -> Result<Box<dyn Mission>, MissionError>,
}

/// The registry: one name per mission module (each has an `ENTRY`). The first is the default
/// (roam: no entities, never complete).
macro_rules! missions {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*
        /// The missions of this crate, in registry order.
        pub const MISSIONS: &[MissionEntry] = &[$($m::ENTRY),*];
    };
}

missions!(roam, formation, hunt);

/// A plug-in's world side: its missions. Implemented by each plug-in (a unit type, with
/// `swarm::plugin::Plugin`) and by tuples of plug-ins (the composition: bins/src/lib.rs).
pub trait Missions {
    fn missions() -> Vec<MissionEntry> {
        Vec::new()
    }
}

impl Missions for () {}

macro_rules! tuple_missions {
    ($($p:ident),+) => {
        impl<$($p: Missions),+> Missions for ($($p,)+) {
            fn missions() -> Vec<MissionEntry> {
                let mut v = Vec::new();
                $(v.extend($p::missions());)+
                v
            }
        }
    };
}

tuple_missions!(A);
tuple_missions!(A, B);
tuple_missions!(A, B, C);
tuple_missions!(A, B, C, D);
tuple_missions!(A, B, C, D, E);
tuple_missions!(A, B, C, D, E, F);
tuple_missions!(A, B, C, D, E, F, G);
tuple_missions!(A, B, C, D, E, F, G, H);

/// The missions this crate's own (registered first; roam is the default) and every plug-in
/// registered after them.
static REGISTRY: std::sync::LazyLock<std::sync::RwLock<Vec<MissionEntry>>> =
    std::sync::LazyLock::new(|| std::sync::RwLock::new(MISSIONS.to_vec()));

/// Registers plug-in `P`'s missions (those whose name is not yet taken), after the others.
pub fn register<P: Missions>() {
    let mut r = REGISTRY.write().unwrap_or_else(|e| e.into_inner());
    for m in P::missions() {
        if !r.iter().any(|x| x.name == m.name) {
            r.push(m);
        }
    }
}

/// Every mission, in registry order (the first is the default).
pub fn all() -> Vec<MissionEntry> {
    REGISTRY.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// The scenario's mission: `run.mission`, or the one its behaviour implies, or roam.
pub fn entry_for(sc: &Scenario) -> Option<MissionEntry> {
    let all = all();
    match &sc.run.mission {
        Some(name) => all.iter().find(|m| m.name == name).copied(),
        None => Some(
            all.iter()
                .find(|m| m.implied_by.contains(&sc.run.behaviour.as_str()))
                .copied()
                .unwrap_or(all[0]),
        ),
    }
}

/// What the scenario's mission's progress counts ("" for none or an unknown mission).
pub fn progress_label(sc: &Scenario) -> &'static str {
    entry_for(sc).map_or("", |m| m.progress_label)
}

/// Checks that `run.mission` names a mission, and the mission's section.
pub fn validate_with(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let Some(m) = entry_for(sc) else {
        let names: Vec<&str> = all().iter().map(|m| m.name).collect();
        return Err(c.err(
            "run.mission",
            format!("= {:?} is unknown: allowed {names:?}", sc.run.mission),
        ));
    };
    (m.validate)(sc, c)
}

/// [`validate_with`], errors naming `source` as where every key came from.
pub fn validate(sc: &Scenario, source: &str) -> Result<(), ConfigError> {
    validate_with(
        sc,
        &Check {
            key_source: &|_| source.to_string(),
        },
    )
}

/// The scenario's mission, set up (the scenario validated beforehand).
pub fn create(sc: &Scenario) -> Result<Box<dyn Mission>, MissionError> {
    let m = entry_for(sc).ok_or_else(|| MissionError::Setup {
        key: "run.mission".into(),
        message: format!(
            "{:?} is unknown (the scenario was not validated)",
            sc.run.mission
        ),
    })?;
    (m.new)(sc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_behaviour_implies_the_mission_unless_one_is_named() {
        let mut sc = Scenario::roam();
        sc.run.behaviour = "hunt".into();
        assert_eq!(entry_for(&sc).unwrap().name, "hunt");
        // A behaviour no registered mission names: roam's (the default).
        sc.run.behaviour = "search".into();
        assert_eq!(entry_for(&sc).unwrap().name, "roam");
        assert_eq!(entry_for(&Scenario::roam()).unwrap().name, "roam");
        let mut sc = Scenario::roam();
        sc.run.mission = Some("formation".into());
        assert_eq!(entry_for(&sc).unwrap().name, "formation");
        sc.run.mission = Some("chess".into());
        let e = validate(&sc, "t.toml").unwrap_err();
        assert_eq!(e.key, "run.mission");
        assert!(e.to_string().contains("formation"), "{e}");
    }
}
