//! One tick as the page draws it: a recording's TickRecord in JSON, with the mission's
//! progress so far.

use serde::Serialize;
use swarm::layer::Mark;
use swarm::radio::RadioCounters;
use swarm::recording::{Event, TickRecord};

#[derive(Debug, Clone, Serialize)]
pub struct Frame<'a> {
    pub tick: u64,
    /// [x, y, heading] of every robot after the tick.
    pub poses: &'a [[f64; 3]],
    pub alive: &'a [u8],
    pub states: &'a [u8],
    pub events: &'a [Event],
    /// The tick's radio outcome (counts for the whole swarm).
    pub radio: &'a RadioCounters,
    /// The mission's marks at the end of the tick (version-5 recordings; else empty).
    pub layer: &'a [Mark],
    /// EntityDone events up to and including this tick.
    pub done: u32,
    /// Version-6 recordings (`--record-deliveries`): per robot, the sender of each message it
    /// was handed this tick, in (sender, seq) order (a sender twice: two messages).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heard: Option<Vec<Vec<u32>>>,
    /// Per robot, the payload bytes of those messages.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heard_bytes: Option<Vec<u64>>,
}

/// Turns tick records into the page's JSON frames, counting the mission's progress.
#[derive(Default)]
pub struct Framer {
    done: u32,
}

impl Framer {
    pub fn json(&mut self, t: &TickRecord) -> String {
        self.done += t
            .events
            .iter()
            .filter(|e| matches!(e, Event::EntityDone { .. }))
            .count() as u32;
        let f = Frame {
            tick: t.tick,
            poses: &t.poses,
            alive: &t.alive,
            states: &t.states,
            events: &t.events,
            radio: &t.radio,
            layer: t.layer.as_deref().unwrap_or(&[]),
            done: self.done,
            heard: t.deliveries.as_ref().map(|d| {
                d.heard
                    .iter()
                    .map(|h| h.iter().map(|m| m.sender).collect())
                    .collect()
            }),
            heard_bytes: t.deliveries.as_ref().map(|d| {
                d.heard
                    .iter()
                    .map(|h| h.iter().map(|m| m.bytes as u64).sum())
                    .collect()
            }),
        };
        // Frames hold only numbers, strings and lists: they always serialise.
        serde_json::to_string(&f).expect("frame JSON")
    }
}
