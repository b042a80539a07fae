//! One tick as the page draws it: a recording's TickRecord in JSON, with the mission's
//! progress so far and, when it grew, what the run has shown so far (for the legend).

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
    /// The mission's progress after this tick: the last `Event::Progress`'s figures
    /// (formation: robots in place of live robots), else the count of EntityDone events up
    /// to and including this tick of the mission's total at the start.
    pub done: u32,
    pub total: u32,
    /// What the run has shown up to this tick, when it grew at this tick (else left out).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seen: Option<&'a Seen>,
    /// Version-6 recordings (`--record-deliveries`): per robot, the sender of each message it
    /// was handed this tick, in (sender, seq) order (a sender twice: two messages).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heard: Option<Vec<Vec<u32>>>,
    /// Per robot, the payload bytes of those messages.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heard_bytes: Option<Vec<u64>>,
}

/// What a run has shown so far, for a legend of only what it has: the display states robots
/// were in, the mission's legend entries whose marks were drawn (by index into
/// `Meta::legend`), whether a robot died.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Seen {
    pub states: Vec<u8>,
    pub legend: Vec<usize>,
    pub dead: bool,
}

/// Whether `m` is drawn as legend entry `entry` shows: the same kind of mark in the same
/// colour. Triangles (robots, coloured by their task or state) match by kind alone.
pub fn is_drawn_as(m: &Mark, entry: &Mark) -> bool {
    fn key(m: &Mark) -> (u8, [u8; 3]) {
        match m {
            Mark::Disc { fill, .. } => (0, *fill),
            Mark::Ring { colour, .. } => (1, *colour),
            Mark::Circle { colour, .. } => (2, *colour),
            Mark::Triangle { .. } => (3, [0; 3]),
            Mark::Path { colour, .. } => (4, *colour),
        }
    }
    key(m) == key(entry)
}

/// Turns tick records into the page's JSON frames, following the mission's progress and
/// what the run has shown.
pub struct Framer {
    done: u32,
    total: u32,
    legend: Vec<Mark>,
    seen: Seen,
}

impl Framer {
    /// For a run whose mission's total is `total` at the start and whose legend shows
    /// `legend` (`Meta::legend`'s marks).
    pub fn new(total: u32, legend: Vec<Mark>) -> Framer {
        Framer {
            done: 0,
            total,
            legend,
            seen: Seen::default(),
        }
    }

    /// What the run has shown so far.
    pub fn seen(&self) -> &Seen {
        &self.seen
    }

    /// Adds what tick `t` shows; whether that grew.
    fn see(&mut self, t: &TickRecord) -> bool {
        let before = self.seen.clone();
        self.seen.dead |= t.alive.contains(&0);
        for s in &t.states {
            if let Err(k) = self.seen.states.binary_search(s) {
                self.seen.states.insert(k, *s);
            }
        }
        for (k, entry) in self.legend.iter().enumerate() {
            let marks = t.layer.as_deref().unwrap_or(&[]);
            if !self.seen.legend.contains(&k) && marks.iter().any(|m| is_drawn_as(m, entry)) {
                self.seen.legend.push(k);
                self.seen.legend.sort_unstable();
            }
        }
        before != self.seen
    }

    pub fn json(&mut self, t: &TickRecord) -> String {
        for e in &t.events {
            match e {
                Event::EntityDone { .. } => self.done += 1,
                Event::Progress { done, total } => (self.done, self.total) = (*done, *total),
                _ => {}
            }
        }
        let grew = self.see(t);
        let f = Frame {
            tick: t.tick,
            poses: &t.poses,
            alive: &t.alive,
            states: &t.states,
            events: &t.events,
            radio: &t.radio,
            layer: t.layer.as_deref().unwrap_or(&[]),
            done: self.done,
            total: self.total,
            seen: grew.then_some(&self.seen),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn tick(k: u64, states: Vec<u8>, events: Vec<Event>, layer: Vec<Mark>) -> TickRecord {
        TickRecord {
            tick: k,
            poses: vec![[0.0; 3]; states.len()],
            alive: vec![1; states.len()],
            states,
            events,
            radio: Default::default(),
            radio_bytes: Default::default(),
            extra: None,
            layer: Some(layer),
            deliveries: None,
        }
    }

    fn ring(colour: [u8; 3]) -> Mark {
        Mark::Ring {
            at: [0.0; 2],
            px: 5,
            colour,
            width: 2,
        }
    }

    #[test]
    fn progress_counts_entity_done_until_a_progress_event_sets_it() {
        let mut f = Framer::new(10, vec![]);
        let done = Event::EntityDone {
            entity: 0,
            robot: 1,
        };
        let v = |s: String| serde_json::from_str::<serde_json::Value>(&s).unwrap();
        let a = v(f.json(&tick(0, vec![0], vec![done.clone(), done], vec![])));
        assert_eq!((&a["done"], &a["total"]), (&2.into(), &10.into()));
        let p = Event::Progress { done: 3, total: 7 };
        let b = v(f.json(&tick(1, vec![0], vec![p], vec![])));
        assert_eq!((&b["done"], &b["total"]), (&3.into(), &7.into()));
        let c = v(f.json(&tick(2, vec![0], vec![], vec![])));
        assert_eq!((&c["done"], &c["total"]), (&3.into(), &7.into()));
    }

    #[test]
    fn a_frame_says_what_the_run_has_shown_when_it_grew() {
        let (red, black) = ([255, 0, 0], [0, 0, 0]);
        let mut f = Framer::new(0, vec![ring(red), ring(black)]);
        let v = |s: String| serde_json::from_str::<serde_json::Value>(&s).unwrap();
        let a = v(f.json(&tick(0, vec![0, 2], vec![], vec![ring(black)])));
        assert_eq!(
            a["seen"],
            serde_json::json!({"states": [0, 2], "legend": [1], "dead": false})
        );
        let b = v(f.json(&tick(1, vec![2, 0], vec![], vec![ring(black)])));
        assert!(b.get("seen").is_none(), "{b}");
        let c = v(f.json(&tick(2, vec![1, 0], vec![], vec![ring(red)])));
        assert_eq!(
            c["seen"],
            serde_json::json!({"states": [0, 1, 2], "legend": [0, 1], "dead": false})
        );
        // A disc of the legend's ring's colour is not the ring.
        let disc = Mark::Disc {
            at: [0.0; 2],
            px: 5,
            fill: red,
            outline: None,
        };
        assert!(!is_drawn_as(&disc, &ring(red)));
    }
}
