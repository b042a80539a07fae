//! CSV: `tick,robot,x,y,heading,state,alive`, one row per robot and tick, in tick then robot
//! order. Numbers are written as Rust prints them (the shortest text that reads back to the
//! same f64), so the file holds the recording's values exactly.

use super::ExportError;
use std::io::Write;
use std::path::Path;
use swarm::recording::TickRecord;

pub const HEADER: &str = "tick,robot,x,y,heading,state,alive";

/// Writes the rows; returns how many (header excluded).
pub fn write(path: &Path, ticks: &[TickRecord]) -> Result<u64, ExportError> {
    let io = |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    writeln!(w, "{HEADER}").map_err(io)?;
    let mut rows = 0;
    for t in ticks {
        for (i, p) in t.poses.iter().enumerate() {
            writeln!(
                w,
                "{},{i},{},{},{},{},{}",
                t.tick,
                p[0],
                p[1],
                p[2],
                t.states.get(i).copied().unwrap_or(0),
                t.alive.get(i).copied().unwrap_or(0)
            )
            .map_err(io)?;
            rows += 1;
        }
    }
    w.flush().map_err(io)?;
    Ok(rows)
}
