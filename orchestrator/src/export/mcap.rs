//! MCAP for Foxglove, zstd-compressed chunks, JSON messages:
//! - `/scene` (`foxglove.SceneUpdate`, one a tick): arena, obstacles, robots as discs with a
//!   heading arrow coloured by state, the mission's marks (`scene.rs`);
//! - `/tf` (`foxglove.FrameTransforms`, one a tick): frame `robot/<i>` of each robot in frame
//!   `world`, to follow a robot;
//! - `/events` (`foxglove.Log`, one per event): deaths, restarts, entities done, ...;
//! - `/swarm/radio` (one a tick): the tick's radio counters, flat numbers to plot;
//! - `/swarm/deliveries` (recordings with deliveries, version 7, `up --record-deliveries`):
//!   per receiver, the messages it was handed (sender, seq, bytes).
//!
//! Log and publish time is simulated time (`clock.rs`), tick 0 at 0; the file's `swarm run`
//! metadata record states seconds per tick and where that comes from, with the scenario.

use super::events::{Described, Severity};
use super::foxglove::{self as fg, FrameTransform, FrameTransforms, Quaternion, Time, Vector3};
use super::{ExportError, Run};
use mcap::records::MessageHeader;
use mcap::{WriteOptions, Writer};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::Path;
use swarm::recording::TickRecord;

const RADIO_SCHEMA: &str = r#"{"type":"object","properties":{
 "tick":{"type":"integer"},"offered":{"type":"integer"},"delivered":{"type":"integer"},
 "dropped_range":{"type":"integer"},"dropped_occluded":{"type":"integer"},
 "dropped_bandwidth":{"type":"integer"},"dropped_loss":{"type":"integer"},
 "malformed":{"type":"integer"},"receiver_dead":{"type":"integer"},
 "in_flight":{"type":"integer"}}}"#;

const DELIVERIES_SCHEMA: &str = r#"{"type":"object","properties":{
 "tick":{"type":"integer"},
 "heard":{"type":"array","items":{"type":"object","properties":{
  "receiver":{"type":"integer"},
  "messages":{"type":"array","items":{"type":"object","properties":{
   "sender":{"type":"integer"},"seq":{"type":"integer"},"bytes":{"type":"integer"}}}}}}}}}"#;

pub const SCENE_TOPIC: &str = "/scene";
pub const TF_TOPIC: &str = "/tf";
pub const EVENTS_TOPIC: &str = "/events";
pub const RADIO_TOPIC: &str = "/swarm/radio";
/// The channel of a recording with deliveries.
pub const DELIVERIES_TOPIC: &str = "/swarm/deliveries";

/// zstd level of the chunks (the crate's default is 0, zstd's own default, 3).
const ZSTD_LEVEL: u32 = 9;

/// The channels of a file, by what they carry.
struct Channels {
    scene: u16,
    tf: u16,
    events: u16,
    radio: u16,
    deliveries: Option<u16>,
}

fn add_channels<W: std::io::Write + std::io::Seek>(
    w: &mut Writer<W>,
    deliveries: bool,
) -> Result<Channels, mcap::McapError> {
    let mut channel = |(name, schema): (&str, &str), topic: &str| {
        let s = w.add_schema(name, "jsonschema", schema.as_bytes())?;
        w.add_channel(s, topic, "json", &BTreeMap::new())
    };
    Ok(Channels {
        scene: channel(fg::SCENE_UPDATE, SCENE_TOPIC)?,
        tf: channel(fg::FRAME_TRANSFORMS, TF_TOPIC)?,
        events: channel(fg::LOG, EVENTS_TOPIC)?,
        radio: channel(("swarm.Radio", RADIO_SCHEMA), RADIO_TOPIC)?,
        deliveries: if deliveries {
            Some(channel(
                ("swarm.Deliveries", DELIVERIES_SCHEMA),
                DELIVERIES_TOPIC,
            )?)
        } else {
            None
        },
    })
}

/// The robots' frames at tick `t`.
fn transforms(t: &TickRecord, time: Time) -> FrameTransforms {
    FrameTransforms {
        transforms: t
            .poses
            .iter()
            .enumerate()
            .map(|(i, p)| FrameTransform {
                timestamp: time,
                parent_frame_id: fg::WORLD_FRAME.to_string(),
                child_frame_id: format!("robot/{i}"),
                translation: Vector3 {
                    x: p[0],
                    y: p[1],
                    z: 0.0,
                },
                rotation: Quaternion::yaw(p[2]),
            })
            .collect(),
    }
}

fn log(d: &Described, time: Time) -> fg::Log {
    fg::Log {
        timestamp: time,
        level: match d.severity {
            Severity::Info => fg::LOG_INFO,
            Severity::Warning => fg::LOG_WARNING,
            Severity::Error => fg::LOG_ERROR,
        },
        message: d.sentence(),
        name: d.name.to_string(),
        file: String::new(),
        line: 0,
    }
}

/// The tick's messages, (channel, JSON), in the order written.
fn messages(run: &Run, c: &Channels, t: &TickRecord, ns: u64) -> Vec<(u16, String)> {
    let time = Time::from_ns(ns);
    let mut out = vec![
        (c.scene, text(&super::scene::update(run, t, ns))),
        (c.tf, text(&transforms(t, time))),
    ];
    for e in &t.events {
        out.push((c.events, text(&log(&Described::of(e), time))));
    }
    // Every counter the recording holds (the schema names those known today).
    let mut radio = serde_json::to_value(t.radio).expect("radio JSON");
    radio["tick"] = t.tick.into();
    out.push((c.radio, radio.to_string()));
    if let Some(ch) = c.deliveries {
        // Receivers that heard something, in id order.
        let heard: Vec<serde_json::Value> = t
            .deliveries
            .as_ref()
            .map_or(&[][..], |d| &d.heard[..])
            .iter()
            .enumerate()
            .filter(|(_, h)| !h.is_empty())
            .map(|(i, h)| json!({"receiver": i, "messages": h}))
            .collect();
        out.push((ch, json!({"tick": t.tick, "heard": heard}).to_string()));
    }
    out
}

/// A message as JSON text (the types hold nothing that fails to serialise).
fn text<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string(v).expect("message JSON")
}

/// Writes the file; returns the number of messages.
pub fn write(path: &Path, run: &Run, ticks: &[TickRecord]) -> Result<u64, ExportError> {
    let io = |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mc = |source| ExportError::Mcap {
        path: path.to_path_buf(),
        source,
    };
    let file = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    let mut w: Writer<_> = WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_level(ZSTD_LEVEL)
        .profile("")
        .create(file)
        .map_err(mc)?;
    let h = &run.header;
    let mut meta = BTreeMap::new();
    meta.insert("scenario".to_string(), h.scenario.clone());
    meta.insert("seed".to_string(), h.seed.to_string());
    meta.insert("robots".to_string(), h.robots.to_string());
    meta.insert("recording_version".to_string(), h.version.to_string());
    meta.insert(
        "seconds_per_tick".to_string(),
        run.clock.seconds_per_tick.to_string(),
    );
    meta.insert("time".to_string(), run.clock.source.to_string());
    w.write_metadata(&mcap::records::Metadata {
        name: "swarm run".into(),
        metadata: meta,
    })
    .map_err(mc)?;
    let deliveries = h.version >= swarm::recording::RECORDING_VERSION_DELIVERIES;
    let channels = add_channels(&mut w, deliveries).map_err(mc)?;
    let mut count = 0u64;
    for t in ticks {
        let ns = run.clock.ns(t.tick);
        for (channel_id, m) in messages(run, &channels, t, ns) {
            w.write_to_known_channel(
                &MessageHeader {
                    channel_id,
                    sequence: t.tick as u32,
                    log_time: ns,
                    publish_time: ns,
                },
                m.as_bytes(),
            )
            .map_err(mc)?;
            count += 1;
        }
    }
    w.finish().map_err(mc)?;
    Ok(count)
}
