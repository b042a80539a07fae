//! The `cbca` behaviour: CBCA (thesis 003 chapter 4, docs/hunting.md sections 4, 5, 8),
//! decentralised, one robot per process, every fact over the radio. The kernels are
//! `crate::cbca` (Algorithms 1 and 2, grouping, loyalty); this module drives them with ticks,
//! the Sense frame and the behaviour API (robot.rs), and reads the scenario's `[cbca]`
//! section: `[cbca.params]` (the kernels' `CbcaParams`), `[[cbca.tasks]]` / `[[cbca.robots]]`
//! (Tables 4.1-4.4 rows) and `[cbca.behaviour]` (this module's `BehaviourParams`).

pub mod liveness;
pub mod messages;
pub mod motion;
pub mod params;
pub mod robot;

#[cfg(test)]
mod driver;
#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};
use swarm::scenario::{Check, ConfigError, Scenario};

use crate::cbca::scenario::CbcaScenario;
pub use params::{BehaviourParams, Prior};
pub use robot::{Cbca, TargetSensing};

/// The registry's name of this behaviour.
pub const NAME: &str = "cbca";

/// The scenario sections it reads (a run refuses any other behaviour's or mission's section).
pub const SECTIONS: &[&str] = &["cbca", "hunt"];

/// How targets appear in the Sense frame (the hunt mission's entity contract): kind
/// `ENTITY_EVADER` = 1, id the thesis's 1-based T_j, the captured flag 1 << 4.
pub const TARGET_SENSING: TargetSensing = TargetSensing {
    kind: 1,
    captured_flag: 1 << 4,
};

/// The `[cbca]` section, parsed.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    pub kernels: CbcaScenario,
    pub behaviour: BehaviourParams,
    pub sensing: TargetSensing,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Raw {
    #[serde(default)]
    params: crate::cbca::CbcaParams,
    #[serde(default)]
    tasks: Vec<crate::cbca::scenario::TaskRow>,
    #[serde(default)]
    robots: Vec<crate::cbca::scenario::RobotRow>,
    #[serde(default)]
    behaviour: BehaviourParams,
}

impl Section {
    /// Parses `sc.cbca`; errors name the key path under `cbca`.
    pub fn of(sc: &Scenario, c: &Check) -> Result<Section, ConfigError> {
        let raw: Raw = serde_path_to_error::deserialize(toml::Value::Table(sc.cbca().clone()))
            .map_err(|e: serde_path_to_error::Error<toml::de::Error>| {
                c.err(
                    &format!("cbca.{}", e.path()),
                    e.inner().message().to_string(),
                )
            })?;
        let kernels = CbcaScenario {
            params: raw.params,
            tasks: raw.tasks,
            robots: raw.robots,
        };
        Ok(Section {
            kernels,
            behaviour: raw.behaviour,
            sensing: TARGET_SENSING,
        })
    }

    fn to_table(&self) -> toml::Table {
        let raw = Raw {
            params: self.kernels.params.clone(),
            tasks: self.kernels.tasks.clone(),
            robots: self.kernels.robots.clone(),
            behaviour: self.behaviour.clone(),
        };
        toml::Table::try_from(raw).expect("the cbca section serialises")
    }
}

/// Checks the `[cbca]` section against the run.
pub fn validate(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    let s = Section::of(sc, c)?;
    let robots = s
        .kernels
        .robots()
        .map_err(|e| c.err("cbca.robots", e.to_string()))?;
    let tasks = s
        .kernels
        .tasks()
        .map_err(|e| c.err("cbca.tasks", e.to_string()))?;
    if robots.len() != sc.run.robots as usize {
        return Err(c.err(
            "cbca.robots",
            format!(
                "holds {} rows but run.robots = {}: one row a robot",
                robots.len(),
                sc.run.robots
            ),
        ));
    }
    if tasks.is_empty() || tasks.len() > swarm::frames::MAX_ENTITIES {
        return Err(c.err(
            "cbca.tasks",
            format!(
                "holds {} rows: allowed 1..={}",
                tasks.len(),
                swarm::frames::MAX_ENTITIES
            ),
        ));
    }
    let b = &s.behaviour;
    c.range_f(
        "cbca.behaviour.ticks_per_time_unit",
        b.ticks_per_time_unit,
        0.0,
        1e6,
        true,
    )?;
    c.range_u("cbca.behaviour.beacon_period", b.beacon_period, 1, 1000)?;
    c.range_u("cbca.behaviour.neighbour_window", b.neighbour_window, 1, 100_000)?;
    c.range_u("cbca.behaviour.quiet_ticks", b.quiet_ticks, 1, 100_000)?;
    c.range_f("cbca.behaviour.commit_bonus", b.commit_bonus, 0.0, 1e12, false)?;
    c.range_f("cbca.behaviour.wait_radius_km", b.wait_radius_km, 0.0, 1e6, false)?;
    c.range_f("cbca.behaviour.ring_radius_km", b.ring_radius_km, 0.0, 1e6, true)?;
    c.range_f("cbca.behaviour.goto_gain", b.goto_gain, 0.0, 1e6, true)?;
    let worst = messages::worst_case_bytes(robots.len(), &tasks, s.kernels.params.max_tasks);
    if worst > sc.radio.max_message_bytes as usize {
        return Err(c.err(
            "radio.max_message_bytes",
            format!(
                "= {} is below the largest CBCA message of this run ({worst} bytes with {} robots and {} targets)",
                sc.radio.max_message_bytes,
                robots.len(),
                tasks.len()
            ),
        ));
    }
    Ok(())
}

/// Writes every parameter of the section, defaults included, into the scenario.
pub fn resolve(sc: &mut Scenario) -> Result<(), ConfigError> {
    let c = Check {
        key_source: &|k| k.to_string(),
    };
    let s = Section::of(sc, &c)?;
    *sc.cbca_mut() = s.to_table();
    Ok(())
}

pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    let c = Check {
        key_source: &|k| k.to_string(),
    };
    let s = Section::of(sc, &c).expect("validated");
    v.visit(&|i| Cbca::new(&s, sc, i))
}
