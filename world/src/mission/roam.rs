//! The empty mission: no entities, never complete (roaming runs last `run.max_ticks`).

use super::{Mission, MissionEntry, MissionError, RunFacts};
use swarm::frames::Sense;
use swarm::recording::Event;
use swarm::scenario::{Check, ConfigError, Scenario};

pub const ENTRY: MissionEntry = MissionEntry {
    name: "roam",
    progress_label: "",
    implied_by: &[],
    sections: &[],
    validate,
    new,
};

fn validate(_sc: &Scenario, _c: &Check) -> Result<(), ConfigError> {
    Ok(())
}

fn new(_sc: &Scenario) -> Result<Box<dyn Mission>, MissionError> {
    Ok(Box::new(Roam))
}

pub struct Roam;

impl Mission for Roam {
    fn name(&self) -> &'static str {
        "roam"
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn sense(&mut self, _robot: u32, _pos: [f64; 2], _out: &mut Sense) {}
    fn update(&mut self, _: u64, _: &[[f64; 3]], _: &[bool], _: &mut Vec<Event>) {}
    fn progress(&self) -> (u32, u32) {
        (0, 0)
    }
    fn complete(&self) -> bool {
        false
    }
    fn end_reason(&self) -> &'static str {
        "completed"
    }
    fn metrics(&self, _facts: &RunFacts) -> Option<serde_json::Value> {
        None
    }
}
