//! `orchestrator export runs/<id> --format csv|events|mcap`: a run's recording in formats other
//! tools read. CSV: one row per robot and tick (pandas, spreadsheets). Events: one row per
//! event of the run (deaths, restarts, entities done, ...). MCAP: Foxglove's well-known schemas
//! (a 3D scene, frame transforms, a log of the events) and the radio counters, in simulated
//! time (Foxglove).

pub mod charts;
pub mod clock;
pub mod csv;
pub mod events;
pub mod foxglove;
pub mod mcap;
pub mod scene;

use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use swarm::recording::{RecordingHeader, TickRecord};

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// One row per robot and tick: recording.csv.
    Csv,
    /// One row per event (deaths, restarts, entities done, ...): events.csv.
    Events,
    /// Foxglove's 3D scene, transforms, event log and the radio counters: recording.mcap.
    Mcap,
}

impl Format {
    /// The file written in the run folder when `--out` is not given.
    pub fn default_file(self) -> &'static str {
        match self {
            Format::Csv => "recording.csv",
            Format::Events => "events.csv",
            Format::Mcap => "recording.mcap",
        }
    }
    /// What the count printed after writing counts.
    fn counted(self) -> &'static str {
        match self {
            Format::Csv => "rows",
            Format::Events => "events",
            Format::Mcap => "messages",
        }
    }
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// The run folder (holds recording.bin).
    pub run: PathBuf,
    /// What to write.
    #[arg(short, long, value_enum)]
    pub format: Format,
    /// Output file [default: the run folder's recording.csv, events.csv or recording.mcap].
    #[arg(short, long)]
    pub out: Option<PathBuf>,
}

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Mcap {
        path: PathBuf,
        source: ::mcap::McapError,
    },
}

/// What the exports need to know of a run besides its ticks: its scenario and mission's names
/// for states and marks, and its clock.
pub struct Run {
    pub header: RecordingHeader,
    pub meta: crate::view::meta::Meta,
    pub clock: clock::SimClock,
}

impl Run {
    /// The name of display state `s` ("" when the mission names none).
    pub fn state_name(&self, s: u8) -> &'static str {
        self.meta
            .states
            .iter()
            .find(|d| d.state == s)
            .map_or("", |d| d.name)
    }
}

/// Reads `run/recording.bin`; an error names the file.
pub fn read_run(run: &Path) -> Result<(Run, Vec<TickRecord>), String> {
    let input = run.join("recording.bin");
    let (header, ticks) = std::fs::File::open(&input)
        .and_then(swarm::recording::read_recording)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    let name = run.display().to_string();
    let meta = crate::view::meta::Meta::of(&header, &name, false)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    let sc = swarm::scenario::Scenario::parse(&header.scenario, "recording.bin header")
        .map_err(|e| format!("{}: {e}", input.display()))?;
    let clock = clock::SimClock::of(&sc);
    Ok((
        Run {
            header,
            meta,
            clock,
        },
        ticks,
    ))
}

pub fn export(a: ExportArgs) -> i32 {
    let (run, ticks) = match read_run(&a.run) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let out = a.out.unwrap_or_else(|| a.run.join(a.format.default_file()));
    let r = match a.format {
        Format::Csv => csv::write(&out, &run, &ticks),
        Format::Events => events::write(&out, &run, &ticks),
        Format::Mcap => mcap::write(&out, &run, &ticks),
    };
    match r {
        Ok(n) => {
            println!(
                "wrote {} ({} {})",
                out.display(),
                crate::progress::grouped(n),
                a.format.counted()
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
