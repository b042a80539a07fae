//! What the page needs to know of a run besides its ticks: the arena, the radio range, the
//! mission's display states, legend and progress label; built from a recording's header.

use super::frame::Framer;
use serde::Serialize;
use swarm::layer::Mark;
use swarm::recording::RecordingHeader;
use swarm::scenario::Scenario;

/// Why a recording cannot be shown.
#[derive(Debug, thiserror::Error)]
pub enum MetaError {
    #[error("the recording's scenario does not read back: {0}")]
    Scenario(#[from] swarm::scenario::ConfigError),
    #[error("the recording's mission cannot be set up: {0}")]
    Mission(#[from] world::mission::MissionError),
}

#[derive(Debug, Clone, Serialize)]
pub struct StateInfo {
    pub state: u8,
    pub name: &'static str,
    pub colour: [u8; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct LegendInfo {
    pub mark: Mark,
    pub label: &'static str,
    /// The label while a live run goes on, where `label` judges the run's end (search's
    /// "target missed" is "target not found yet" until the run is over).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub running_label: Option<&'static str>,
}

/// Legend labels that judge the run's end, and what the page says instead while a live run
/// goes on: (mission, label, label while running).
pub const RUNNING_LABELS: &[(&str, &str, &str)] =
    &[("search", "target missed", "target not found yet")];

/// The run as the page sees it (`/api/meta`, and `window.RUN.meta` of `/run.js`).
#[derive(Debug, Clone, Serialize)]
pub struct Meta {
    pub run: String,
    /// A live run (`up --view`): more ticks come over `/api/stream`; robots can be killed.
    pub live: bool,
    pub robots: u32,
    pub seed: u64,
    pub behaviour: String,
    pub mission: &'static str,
    pub recording_version: u32,
    pub max_ticks: u64,
    /// Ticks per second of the run's pacing (0: unpaced).
    pub tick_hz: f64,
    pub arena: [f64; 2],
    pub start_region: [f64; 4],
    /// The start region means something on the page: robots were placed in it (the mission
    /// does not place them itself) and it is smaller than the arena.
    pub start_region_shown: bool,
    pub obstacles: Vec<Vec<[f64; 2]>>,
    /// Disc obstacles: (centre, radius).
    pub discs: Vec<([f64; 2], f64)>,
    pub comm_radius: f64,
    /// Robot body radius (0: point robots).
    pub robot_radius: f64,
    /// Empty: robots coloured by id.
    pub states: Vec<StateInfo>,
    pub legend: Vec<LegendInfo>,
    pub progress_label: &'static str,
    /// What the mission counts in all at the start (search: targets); each frame carries
    /// its done count and total after the tick (`frame::Frame`).
    pub progress_total: u32,
    /// The recording says who heard whom each tick (version 7, `--record-deliveries`): the
    /// frames carry `heard`.
    pub deliveries: bool,
}

impl Meta {
    pub fn of(header: &RecordingHeader, run: &str, live: bool) -> Result<Meta, MetaError> {
        let sc = Scenario::parse(&header.scenario, "recording.bin header")?;
        let m = world::mission::create(&sc)?;
        Ok(Meta {
            run: run.to_string(),
            live,
            robots: header.robots,
            seed: header.seed,
            behaviour: sc.run.behaviour.clone(),
            mission: m.name(),
            recording_version: header.version,
            max_ticks: sc.run.max_ticks,
            tick_hz: sc.runtime.tick_hz,
            arena: [sc.arena.width, sc.arena.height],
            start_region: sc.arena.start_region,
            start_region_shown: m.start_poses(&sc).is_none()
                && sc.arena.start_region != [0.0, 0.0, sc.arena.width, sc.arena.height],
            obstacles: sc
                .arena
                .obstacles
                .iter()
                .map(|o| o.points.clone())
                .collect(),
            discs: sc
                .arena
                .discs
                .iter()
                .map(|d| (d.centre, d.radius))
                .collect(),
            comm_radius: sc.radio.comm_radius,
            robot_radius: sc.robot.radius,
            states: m
                .display_states()
                .iter()
                .map(|d| StateInfo {
                    state: d.state,
                    name: d.name,
                    colour: d.colour,
                })
                .collect(),
            legend: m
                .legend()
                .into_iter()
                .map(|e| LegendInfo {
                    mark: e.mark,
                    label: e.label,
                    running_label: RUNNING_LABELS
                        .iter()
                        .find(|(mission, label, _)| *mission == m.name() && *label == e.label)
                        .map(|r| r.2),
                })
                .collect(),
            progress_label: world::mission::progress_label(&sc),
            progress_total: m.progress().1,
            deliveries: header.version >= swarm::recording::RECORDING_VERSION_DELIVERIES,
        })
    }
}

impl Meta {
    /// The framer of this run's ticks (its progress total, its legend's marks).
    pub fn framer(&self) -> Framer {
        Framer::new(
            self.progress_total,
            self.legend.iter().map(|l| l.mark.clone()).collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_label_said_otherwise_while_running_is_its_missions_label() {
        for (mission, label, _) in RUNNING_LABELS {
            let mut sc = Scenario::default();
            sc.run.mission = Some(mission.to_string());
            let m = world::mission::create(&sc).unwrap();
            assert!(
                m.legend().iter().any(|e| e.label == *label),
                "{mission} has no legend label {label:?}"
            );
        }
    }
}
