//! The run folder: scenario.toml, recording.bin, summary.json, run.svg.
//!
//! Every error names its file. scenario.toml, summary.json and run.svg are written whole
//! under a temporary name and renamed ([`write_atomic`]): a full disk leaves the file as it
//! was or absent, never empty or cut short. recording.bin is written as the run goes (a live
//! viewer reads it as it grows); a write that fails ends the run naming it.

use crate::body::BodySummary;
use crate::metrics::{spread, MissionMetrics};
use crate::mission::RunFacts;
use crate::world::{Fault, World, REJECT_NAMES};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use swarm::radio::RadioCounters;
use swarm::recording::{RecordingHeader, RecordingWriter, TickRecord};

/// A file of the run folder that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct OutputError {
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

/// The operating system's error under `e`, if some error in its chain has one: the
/// recording's encoder wraps the file's error in its own (kind Other, printed as
/// `Io { inner: Os { code: 28, .. }, index: 20 }`), which names neither the cause plainly
/// nor the file.
fn os_cause(e: std::io::Error) -> std::io::Error {
    if e.raw_os_error().is_some() {
        return e;
    }
    let mut cause: Option<&(dyn std::error::Error + 'static)> = e.get_ref().map(|x| x as _);
    while let Some(c) = cause {
        if let Some(code) = c
            .downcast_ref::<std::io::Error>()
            .and_then(|io| io.raw_os_error())
        {
            return std::io::Error::from_raw_os_error(code);
        }
        cause = c.source();
    }
    e
}

/// Wraps an I/O error so that it names `path` (its kind kept: a full disk stays StorageFull).
pub fn named(path: &Path) -> impl FnOnce(std::io::Error) -> std::io::Error + '_ {
    move |source| {
        let source = os_cause(source);
        std::io::Error::new(
            source.kind(),
            OutputError {
                path: path.to_path_buf(),
                source,
            },
        )
    }
}

/// The temporary name `path` is written under before its rename: hidden, in the same folder
/// (a rename within one file system is atomic).
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp"))
}

/// Writes `bytes` to `path` whole or not at all: to a temporary name, flushed to the disk,
/// then renamed over `path`. On an error the temporary file is removed and `path` is left as
/// it was; the error names `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let written = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        // Data on the disk before the rename: a delayed-allocation file system reports a
        // full disk here, not at close (which nobody checks).
        f.sync_data()?;
        std::fs::rename(&tmp, path)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written.map_err(named(path))
}

/// Wall-clock facts of a run, measured by the executor.
#[derive(Debug, Clone, Default)]
pub struct Timing {
    pub wall_seconds: f64,
    /// Seconds spent in the tick loop (excludes start-up and outputs).
    pub loop_seconds: f64,
    pub startup_seconds: f64,
    /// Duration of every tick, nanoseconds.
    pub tick_ns: Vec<u64>,
    /// Real-time mode: ticks the world itself released after their deadline (the world's
    /// own work, sensing and the medium, took longer than the period).
    pub late_releases: u64,
}

/// Real-time mode's figures in summary.json (absent for lock-step runs).
#[derive(Debug, Clone, Serialize)]
pub struct RealtimeSummary {
    /// The clock's rate, ticks per second (`runtime.realtime_hz`).
    pub hz: f64,
    /// Deadlines missed, all robots.
    pub deadline_misses: u64,
    /// Deadlines missed by each robot (index = robot).
    pub misses_per_robot: Vec<u64>,
    /// (live robot, tick) pairs: deadline_misses / robot_ticks is the miss rate.
    pub robot_ticks: u64,
    pub miss_rate: f64,
    /// Actions read after their tick's deadline (their messages went out then).
    pub late_actions: u64,
    /// Ticks the world released after their own deadline.
    pub late_releases: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct TickTimes {
    pub p50_us: f64,
    pub p99_us: f64,
    pub max_us: f64,
}

pub fn percentile(sorted: &[u64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let idx = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[idx] as f64
}

#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub run_id: String,
    pub executor: String,
    pub behaviour: String,
    pub robots: u32,
    pub seed: u64,
    pub ticks: u64,
    pub max_ticks: u64,
    /// How the run ended: "completed", "interrupted", "failed: ...".
    pub end: String,
    pub wall_seconds: f64,
    pub startup_seconds: f64,
    pub ticks_per_second: f64,
    /// Ticks per second after the warm-up (the first max(10, 5 %) ticks, which include making
    /// the initial radio links).
    pub steady_ticks_per_second: f64,
    pub tick_time: TickTimes,
    pub messages: RadioCounters,
    /// The same counters in payload bytes (each (message, receiver) pair counts its message's
    /// encoded length; the 40-byte header of each is not counted).
    pub message_bytes: RadioCounters,
    pub rejected_actions: BTreeMap<String, u64>,
    pub blocked_moves: u64,
    pub distance_travelled: f64,
    pub alive_at_end: u32,
    pub faults: Vec<Fault>,
    /// Real-time mode only: deadline misses per robot and in all.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub realtime: Option<RealtimeSummary>,
    /// The run's worst clearances and overlaps (robots with a body only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<BodySummary>,
    pub mission: MissionMetrics,
}

/// Where a run's outputs go: the run folder, or nowhere but the returned Summary (sweeps of
/// thousands of runs keep only their summaries).
pub struct RunOutputs {
    pub dir: Option<PathBuf>,
    rec: Option<RecordingWriter<File>>,
    /// recording.bin's path (its errors name it).
    rec_path: PathBuf,
    /// The recording holds the mission's layer per tick (version 5).
    layer: bool,
}

impl RunOutputs {
    /// The run folder for `world`'s run (its scenario, and its recording version).
    pub fn create(dir: &Path, world: &World) -> std::io::Result<RunOutputs> {
        let sc = &world.sc;
        std::fs::create_dir_all(dir).map_err(named(dir))?;
        write_atomic(&dir.join("scenario.toml"), sc.to_toml().as_bytes())?;
        let version = world.recording_version();
        let header = RecordingHeader {
            version,
            robots: sc.run.robots,
            seed: sc.run.seed,
            scenario: sc.to_toml(),
        };
        let rec_path = dir.join("recording.bin");
        let rec = File::create(&rec_path)
            .and_then(|f| RecordingWriter::new(f, &header))
            .map_err(named(&rec_path))?;
        Ok(RunOutputs {
            dir: Some(dir.to_path_buf()),
            rec: Some(rec),
            rec_path,
            layer: version >= swarm::recording::RECORDING_VERSION_LAYER,
        })
    }

    /// No files: `finish` only returns the Summary.
    pub fn summary_only() -> RunOutputs {
        RunOutputs {
            dir: None,
            rec: None,
            rec_path: PathBuf::new(),
            layer: false,
        }
    }

    /// Writes tick record `t` of `world` (which has applied it: its mission's layer is the
    /// tick's, for a version-5 recording).
    pub fn push(&mut self, t: &TickRecord, world: &World) -> std::io::Result<()> {
        match self.rec.as_mut() {
            Some(r) if self.layer => r.push_with_layer(t, Some(&world.mission.live_layer())),
            Some(r) => r.push(t),
            None => Ok(()),
        }
        .map_err(named(&self.rec_path))
    }

    /// Every tick reaches recording.bin as it is pushed, for a live viewer that reads the
    /// file as it grows (`orchestrator up --view`); the bytes are the same.
    pub fn flush_each_tick(&mut self) {
        if let Some(r) = self.rec.as_mut() {
            r.flush_each_tick(true);
        }
    }

    /// Closes the recording and writes summary.json and run.svg.
    pub fn finish(
        mut self,
        world: &mut World,
        timing: &Timing,
        run_id: &str,
        executor: &str,
        end: &str,
    ) -> std::io::Result<Summary> {
        if let Some(r) = self.rec.take() {
            r.finish().map_err(named(&self.rec_path))?;
        }
        world.finish_radio();
        let warmup = (timing.tick_ns.len() / 20)
            .max(10)
            .min(timing.tick_ns.len());
        let steady_ns: u64 = timing.tick_ns[warmup..].iter().sum();
        let steady_ticks_per_second = if steady_ns > 0 {
            (timing.tick_ns.len() - warmup) as f64 / (steady_ns as f64 / 1e9)
        } else {
            0.0
        };
        let mut sorted = timing.tick_ns.clone();
        sorted.sort_unstable();
        let ticks = world.tick;
        let summary = Summary {
            run_id: run_id.to_string(),
            executor: executor.to_string(),
            behaviour: world.sc.run.behaviour.clone(),
            robots: world.n as u32,
            seed: world.sc.run.seed,
            ticks,
            max_ticks: world.sc.run.max_ticks,
            end: end.to_string(),
            wall_seconds: timing.wall_seconds,
            startup_seconds: timing.startup_seconds,
            ticks_per_second: if timing.loop_seconds > 0.0 {
                ticks as f64 / timing.loop_seconds
            } else {
                0.0
            },
            steady_ticks_per_second,
            tick_time: TickTimes {
                p50_us: percentile(&sorted, 0.5) / 1e3,
                p99_us: percentile(&sorted, 0.99) / 1e3,
                max_us: sorted.last().copied().unwrap_or(0) as f64 / 1e3,
            },
            messages: world.radio,
            message_bytes: world.radio_bytes,
            rejected_actions: REJECT_NAMES
                .iter()
                .zip(world.rejected)
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
            blocked_moves: world.blocked_moves,
            distance_travelled: world.distance_travelled,
            alive_at_end: world.alive_count(),
            faults: world.faults.clone(),
            realtime: world.sc.runtime.is_realtime().then(|| RealtimeSummary {
                hz: world.sc.runtime.realtime_hz,
                deadline_misses: world.total_misses(),
                misses_per_robot: world.misses.clone(),
                robot_ticks: world.robot_ticks,
                miss_rate: if world.robot_ticks > 0 {
                    world.total_misses() as f64 / world.robot_ticks as f64
                } else {
                    0.0
                },
                late_actions: world.late_actions,
                late_releases: timing.late_releases,
            }),
            body: world.body,
            mission: {
                let mut m = spread(&world.coverage, &world.poses, &world.alive);
                let facts = RunFacts {
                    ticks,
                    distance_travelled: world.distance_travelled,
                };
                if let Some(own) = world.mission.metrics(&facts) {
                    m.own.insert(world.mission.name().to_string(), own);
                }
                m
            },
        };
        if let Some(dir) = &self.dir {
            write_atomic(
                &dir.join("summary.json"),
                serde_json::to_string_pretty(&summary)
                    .map_err(std::io::Error::other)?
                    .as_bytes(),
            )?;
            let svg = dir.join("run.svg");
            let picture =
                crate::svg::svg_text(world).map_err(|e| named(&svg)(std::io::Error::other(e)))?;
            write_atomic(&svg, picture.as_bytes())?;
        }
        Ok(summary)
    }
}
