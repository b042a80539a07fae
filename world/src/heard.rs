//! Who heard whom: the messages the medium hands each robot at a tick, as the recording keeps
//! them when `runtime.record_deliveries` is on (recording version 7, for the viewer).

use crate::medium::TickAir;
use swarm::recording::{Heard, TickDeliveries};

/// The deliveries of the air `due` at a tick to `n` robots. `took(i)` is Some(malformed count
/// robot i reported) when robot i took its messages (alive, with a valid action this tick),
/// None when they are lost with it (`receiver_dead`): it is then listed as hearing nothing.
pub fn deliveries(
    due: Option<&TickAir>,
    n: usize,
    took: impl Fn(usize) -> Option<u32>,
) -> TickDeliveries {
    let mut d = TickDeliveries {
        heard: vec![Vec::new(); n],
        malformed: Vec::new(),
    };
    let Some(air) = due else {
        return d;
    };
    for (i, heard) in d.heard.iter_mut().enumerate().take(air.robots()) {
        let listed = air.deliveries(i as u32);
        if listed.is_empty() {
            continue;
        }
        let Some(bad) = took(i) else {
            continue;
        };
        // From the headers and payload ranges only: a lent air's payloads are elsewhere.
        heard.extend(listed.iter().filter_map(|&m| {
            air.messages.get(m as usize).map(|(h, payload)| Heard {
                sender: h.sender,
                seq: h.seq,
                bytes: payload.len() as u32,
            })
        }));
        if bad > 0 {
            d.malformed.push((i as u32, bad.min(listed.len() as u32)));
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarm::frames::RadioHeader;

    /// Three robots; robot 0 sent two messages (seq 5: 3 bytes, seq 6: 1 byte), robot 2 one
    /// (seq 9: 2 bytes). Robot 1 is handed all three, robot 2 both of robot 0's, robot 0
    /// robot 2's.
    fn air() -> TickAir {
        let h = |sender, seq, len| RadioHeader {
            sender,
            seq,
            len,
            ..Default::default()
        };
        TickAir {
            tick: 4,
            messages: vec![(h(0, 5, 3), 0..3), (h(0, 6, 1), 3..4), (h(2, 9, 2), 4..6)],
            bytes: vec![0; 6],
            start: vec![0, 1, 4, 6],
            index: vec![2, 0, 1, 2, 0, 1],
            bytes_to: vec![2, 6, 4],
            lent: false,
        }
    }

    #[test]
    fn each_receiver_lists_what_it_was_handed_in_order_and_a_dead_one_nothing() {
        let heard = |sender, seq, bytes| Heard { sender, seq, bytes };
        // Robot 2 is dead; robot 1 reports one message malformed.
        let d = deliveries(Some(&air()), 3, |i| match i {
            0 => Some(0),
            1 => Some(1),
            _ => None,
        });
        assert_eq!(
            d.heard,
            vec![
                vec![heard(2, 9, 2)],
                vec![heard(0, 5, 3), heard(0, 6, 1), heard(2, 9, 2)],
                vec![],
            ]
        );
        assert_eq!(d.malformed, vec![(1, 1)]);
        // No air due: every robot heard nothing.
        let none = deliveries(None, 3, |_| Some(0));
        assert_eq!(none.heard, vec![Vec::<Heard>::new(); 3]);
    }
}
