//! The events export: `tick,time_s,event,robot,entity,detail`, one row per event of the
//! recording, in tick order and, within a tick, as the world logged them. `event` is a
//! snake_case name (robot_died, robot_restarted, action_rejected, move_blocked, entity_done,
//! declared, deadline_missed, progress); `robot` is empty for the mission's own progress
//! (done of total); `entity` is set for entity_done only; `detail` is the cause of a
//! death, the reason of a rejection, the flags of a declaration. The MCAP's `/events` log
//! says the same in words ([`Described::sentence`]).

use super::csv::csv_error;
use super::{ExportError, Run};
use std::path::Path;
use swarm::recording::{Event, TickRecord};

pub const HEADER: [&str; 6] = ["tick", "time_s", "event", "robot", "entity", "detail"];

/// How bad an event is, for the MCAP log's level.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    Info,
    Warning,
    Error,
}

/// An event as the exports write it.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    pub name: &'static str,
    /// The robot it is about (None: the mission's, e.g. its progress).
    pub robot: Option<u32>,
    pub entity: Option<u32>,
    pub detail: String,
    pub severity: Severity,
}

impl Described {
    pub fn of(e: &Event) -> Described {
        let severity = match e {
            Event::RobotDied { .. } => Severity::Error,
            Event::ActionRejected { .. } | Event::DeadlineMissed { .. } => Severity::Warning,
            _ => Severity::Info,
        };
        Described {
            name: e.name(),
            robot: e.robot(),
            entity: e.entity(),
            detail: e.detail(),
            severity,
        }
    }
    /// One line for a log: "robot 3 robot_died: process died".
    pub fn sentence(&self) -> String {
        let mut s = match self.robot {
            Some(r) => format!("robot {r} {}", self.name),
            None => format!("mission {}", self.name),
        };
        if let Some(e) = self.entity {
            s += &format!(" entity {e}");
        }
        if !self.detail.is_empty() {
            s += &format!(": {}", self.detail);
        }
        s
    }
}

/// Writes the rows; returns how many (header excluded).
pub fn write(path: &Path, run: &Run, ticks: &[TickRecord]) -> Result<u64, ExportError> {
    let err = csv_error(path);
    let mut w = ::csv::Writer::from_path(path).map_err(&err)?;
    w.write_record(HEADER).map_err(&err)?;
    let mut rows = 0;
    for t in ticks {
        let time = run.clock.seconds(t.tick).to_string();
        for e in &t.events {
            let d = Described::of(e);
            w.write_record([
                t.tick.to_string().as_str(),
                &time,
                d.name,
                &d.robot.map(|r| r.to_string()).unwrap_or_default(),
                &d.entity.map(|e| e.to_string()).unwrap_or_default(),
                &d.detail,
            ])
            .map_err(&err)?;
            rows += 1;
        }
    }
    w.flush().map_err(|source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(rows)
}
