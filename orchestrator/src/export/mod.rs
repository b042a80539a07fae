//! `orchestrator export runs/<id> --format csv|mcap`: a run's recording in formats other tools
//! read. CSV: one row per robot and tick (pandas, spreadsheets). MCAP: JSON-schema channels of
//! poses, mission entities and radio counters, one message per tick each (Foxglove).

pub mod charts;
pub mod csv;
pub mod mcap;

use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Csv,
    Mcap,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// The run folder (holds recording.bin).
    pub run: PathBuf,
    #[arg(long, value_enum)]
    pub format: Format,
    /// Output file (default: the run folder's recording.csv / recording.mcap).
    #[arg(long)]
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

pub fn export(a: ExportArgs) -> i32 {
    let input = a.run.join("recording.bin");
    let rec = std::fs::File::open(&input).and_then(swarm::recording::read_recording);
    let (header, ticks) = match rec {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {}: {e}", input.display());
            return 2;
        }
    };
    let ext = match a.format {
        Format::Csv => "csv",
        Format::Mcap => "mcap",
    };
    let out = a
        .out
        .unwrap_or_else(|| a.run.join(format!("recording.{ext}")));
    let r = match a.format {
        Format::Csv => csv::write(&out, &ticks),
        Format::Mcap => mcap::write(&out, &header, &ticks),
    };
    match r {
        Ok(rows) => {
            println!(
                "wrote {} ({rows} {})",
                out.display(),
                match a.format {
                    Format::Csv => "rows",
                    Format::Mcap => "messages",
                }
            );
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
