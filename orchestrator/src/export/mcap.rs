//! MCAP with JSON messages and JSON-schema channels, one message per tick on each:
//! `/swarm/poses` (every robot's pose, state, alive), `/swarm/entities` (the mission's marks:
//! search targets found and not, ...) and `/swarm/radio` (the tick's radio counters); a
//! recording with deliveries (version 7, `up --record-deliveries`) adds `/swarm/deliveries`
//! (per receiver, the messages it was handed: sender, seq, bytes). The recording's header is
//! the file's `scenario` metadata record.

use super::ExportError;
use mcap::records::MessageHeader;
use mcap::{WriteOptions, Writer};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::Path;
use swarm::recording::{RecordingHeader, TickRecord};

/// A tick's log time when the run is unpaced (runtime.tick_hz = 0): the recording holds no
/// wall-clock time, so ticks are shown 0.1 s apart. A paced run's ticks are 1/tick_hz apart.
const UNPACED_TICK_NS: u64 = 100_000_000;

const POSES_SCHEMA: &str = r#"{"type":"object","properties":{
 "tick":{"type":"integer"},
 "robots":{"type":"array","items":{"type":"object","properties":{
  "id":{"type":"integer"},"x":{"type":"number"},"y":{"type":"number"},
  "heading":{"type":"number"},"state":{"type":"integer"},"alive":{"type":"boolean"}}}}}}"#;

const ENTITIES_SCHEMA: &str = r#"{"type":"object","properties":{
 "tick":{"type":"integer"},
 "marks":{"type":"array","items":{"type":"object","properties":{
  "kind":{"type":"string","enum":["Disc","Ring","Circle","Triangle","Path"]},
  "at":{"type":"array","items":{"type":"number"}},
  "colour":{"type":"array","items":{"type":"integer"}}}}}}}"#;

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

/// The channels, in the order their messages are written each tick.
pub const TOPICS: [&str; 3] = ["/swarm/poses", "/swarm/entities", "/swarm/radio"];
/// The channel of a recording with deliveries, written after the others each tick.
pub const DELIVERIES_TOPIC: &str = "/swarm/deliveries";

fn tick_ns(header: &RecordingHeader) -> u64 {
    let hz = swarm::scenario::Scenario::parse(&header.scenario, "recording.bin header")
        .map(|s| s.runtime.tick_hz)
        .unwrap_or(0.0);
    if hz > 0.0 {
        (1e9 / hz).round() as u64
    } else {
        UNPACED_TICK_NS
    }
}

/// A mark as an object with its kind named (`{"kind": "Disc", "at": ..., ...}`).
fn mark_json(m: &swarm::layer::Mark) -> serde_json::Value {
    let v = serde_json::to_value(m).expect("mark JSON");
    match v {
        serde_json::Value::Object(o) if o.len() == 1 => {
            let (kind, mut body) = o.into_iter().next().expect("one entry");
            if let Some(b) = body.as_object_mut() {
                b.insert("kind".into(), kind.into());
            }
            body
        }
        v => v,
    }
}

/// Writes the file; returns the number of messages.
pub fn write(
    path: &Path,
    header: &RecordingHeader,
    ticks: &[TickRecord],
) -> Result<u64, ExportError> {
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
        .compression(None)
        .profile("")
        .create(file)
        .map_err(mc)?;
    let mut meta = BTreeMap::new();
    meta.insert("scenario".to_string(), header.scenario.clone());
    meta.insert("seed".to_string(), header.seed.to_string());
    meta.insert("robots".to_string(), header.robots.to_string());
    meta.insert("recording_version".to_string(), header.version.to_string());
    w.write_metadata(&mcap::records::Metadata {
        name: "swarm run".into(),
        metadata: meta,
    })
    .map_err(mc)?;
    let schemas = [
        ("swarm.Poses", POSES_SCHEMA),
        ("swarm.Entities", ENTITIES_SCHEMA),
        ("swarm.Radio", RADIO_SCHEMA),
    ];
    let mut channels = [0u16; 3];
    for (k, (name, schema)) in schemas.iter().enumerate() {
        let s = w
            .add_schema(name, "jsonschema", schema.as_bytes())
            .map_err(mc)?;
        channels[k] = w
            .add_channel(s, TOPICS[k], "json", &BTreeMap::new())
            .map_err(mc)?;
    }
    let deliveries = if header.version >= swarm::recording::RECORDING_VERSION_DELIVERIES {
        let s = w
            .add_schema(
                "swarm.Deliveries",
                "jsonschema",
                DELIVERIES_SCHEMA.as_bytes(),
            )
            .map_err(mc)?;
        Some(
            w.add_channel(s, DELIVERIES_TOPIC, "json", &BTreeMap::new())
                .map_err(mc)?,
        )
    } else {
        None
    };
    let dt = tick_ns(header);
    let mut count = 0u64;
    for t in ticks {
        let robots: Vec<serde_json::Value> = t
            .poses
            .iter()
            .enumerate()
            .map(|(i, p)| {
                json!({"id": i, "x": p[0], "y": p[1], "heading": p[2],
                       "state": t.states.get(i).copied().unwrap_or(0),
                       "alive": t.alive.get(i).copied().unwrap_or(0) == 1})
            })
            .collect();
        let marks: Vec<serde_json::Value> = t
            .layer
            .as_deref()
            .unwrap_or(&[])
            .iter()
            .map(mark_json)
            .collect();
        // Every counter the recording holds (the schema names those known today).
        let mut radio = serde_json::to_value(t.radio).expect("radio JSON");
        radio["tick"] = t.tick.into();
        let mut msgs = vec![
            (channels[0], json!({"tick": t.tick, "robots": robots})),
            (channels[1], json!({"tick": t.tick, "marks": marks})),
            (channels[2], radio),
        ];
        if let Some(c) = deliveries {
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
            msgs.push((c, json!({"tick": t.tick, "heard": heard})));
        }
        let time = t.tick * dt;
        for (channel_id, m) in &msgs {
            w.write_to_known_channel(
                &MessageHeader {
                    channel_id: *channel_id,
                    sequence: t.tick as u32,
                    log_time: time,
                    publish_time: time,
                },
                m.to_string().as_bytes(),
            )
            .map_err(mc)?;
            count += 1;
        }
    }
    w.finish().map_err(mc)?;
    Ok(count)
}
