//! CSV: `tick,time_s,robot,x,y,heading,state,state_name,alive`, one row per robot and tick, in
//! tick then robot order. `time_s` is simulated time (`clock.rs`); `state_name` is the
//! mission's name of the display state `state` (empty when it names none). Numbers are
//! written as Rust prints them (the shortest text that reads back to the same f64), so the
//! file holds the recording's values exactly.

use super::{ExportError, Run};
use std::path::Path;
use swarm::recording::TickRecord;

pub const HEADER: [&str; 9] = [
    "tick",
    "time_s",
    "robot",
    "x",
    "y",
    "heading",
    "state",
    "state_name",
    "alive",
];

/// A CSV writer's error as the export's (the csv crate wraps I/O errors).
pub fn csv_error(path: &Path) -> impl Fn(::csv::Error) -> ExportError + '_ {
    move |e| ExportError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
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
        for (i, p) in t.poses.iter().enumerate() {
            let state = t.states.get(i).copied().unwrap_or(0);
            w.write_record([
                t.tick.to_string().as_str(),
                &time,
                &i.to_string(),
                &p[0].to_string(),
                &p[1].to_string(),
                &p[2].to_string(),
                &state.to_string(),
                run.state_name(state),
                &t.alive.get(i).copied().unwrap_or(0).to_string(),
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
