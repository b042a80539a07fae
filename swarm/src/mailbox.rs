//! The in-process executor's radio: what iceoryx2 carries between processes, carried in memory.
//!
//! Senders encode their messages into an [`Air`] exactly as into loaned shared-memory slots.
//! After the tick, the [`Mailbox`] decodes every message once and keeps it while it can still
//! be due; each receiver's runtime ([`crate::AgentRuntime::ingest_mailbox`]) makes the same
//! range / loss / link decisions as for a message taken off a link, but holds an index into the
//! mailbox instead of its own decoded copy. At N = 100 a message has ~50 receivers: decoding,
//! cloning and dropping it once per receiver was most of the in-process radio's cost.

use crate::behaviour::{decode, decode_in, RadioTx, Received};
use crate::blob::AsBytes;
use crate::frames::RadioHeader;
use serde::de::DeserializeOwned;
use std::collections::VecDeque;
use std::sync::Arc;

/// Messages sent in one tick: headers (with the offset of their payload) and the payloads.
#[derive(Default)]
pub struct Air {
    headers: Vec<(RadioHeader, usize)>,
    bytes: Vec<u8>,
}

impl RadioTx for Air {
    fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
        let at = self.bytes.len();
        self.bytes.resize(at + h.len as usize, 0);
        fill(&mut self.bytes[at..]);
        self.headers.push((*h, at));
    }
}

impl Air {
    /// The messages in the order sent: header and payload.
    pub fn messages(&self) -> impl Iterator<Item = (&RadioHeader, &[u8])> + '_ {
        self.headers
            .iter()
            .map(|(h, at)| (h, &self.bytes[*at..*at + h.len as usize]))
    }

    pub fn clear(&mut self) {
        self.headers.clear();
        self.bytes.clear();
    }

    /// Appends another buffer's messages after ours (in their order).
    pub fn append(&mut self, other: &Air) {
        let base = self.bytes.len();
        self.bytes.extend_from_slice(&other.bytes);
        self.headers
            .extend(other.headers.iter().map(|(h, at)| (*h, at + base)));
    }

    pub fn len(&self) -> usize {
        self.headers.len()
    }

    pub fn is_empty(&self) -> bool {
        self.headers.is_empty()
    }
}

/// The messages of the last `delay + 1` ticks, decoded, grouped by sender.
pub struct Mailbox<M> {
    /// Headers and decoded payloads (None: malformed), oldest first; entry i has the index
    /// `base + i`. Apart, since receivers read every header but only the messages they get.
    headers: VecDeque<RadioHeader>,
    msgs: VecDeque<Option<Received<M>>>,
    base: u64,
    /// (tick, index of its first message) of each tick kept, oldest first.
    ticks: VecDeque<(u64, u64)>,
    /// Messages of the latest tick by sender: those of robot r are the indices
    /// `latest_first + by_sender[r] .. latest_first + by_sender[r + 1]`.
    by_sender: Vec<u32>,
    latest_first: u64,
    /// Ticks kept: a message sent at t is due at t + 1 + delay.
    keep: u64,
    /// Scratch of `post`: message order grouped by sender, next free place per sender.
    order: Vec<u32>,
    next: Vec<u32>,
    /// Decode each tick's messages in a shared copy of its bytes, so that their Blob fields are
    /// views into it (the behaviour's `zero_copy()`).
    zero_copy: bool,
}

impl<M: DeserializeOwned> Mailbox<M> {
    /// A mailbox for robots `0..robots` and a radio delay of `delay_ticks`.
    pub fn new(robots: usize, delay_ticks: u64) -> Mailbox<M> {
        Mailbox {
            headers: VecDeque::new(),
            msgs: VecDeque::new(),
            base: 0,
            ticks: VecDeque::new(),
            by_sender: vec![0; robots + 1],
            latest_first: 0,
            keep: delay_ticks + 1,
            order: Vec::new(),
            next: Vec::new(),
            zero_copy: false,
        }
    }

    /// Zero-copy receive (see [`crate::Behaviour::zero_copy`]): each tick's bytes are copied
    /// once into a shared buffer, and every receiver's Blob fields are views into it.
    pub fn zero_copy(mut self, on: bool) -> Mailbox<M> {
        self.zero_copy = on;
        self
    }

    /// Posts the messages sent at `tick` (decoding each once) and forgets those that can no
    /// longer be due at a later tick. Messages of one sender keep their order.
    pub fn post(&mut self, tick: u64, air: &Air) {
        while let Some(&(t, _)) = self.ticks.front() {
            if t + self.keep > tick {
                break;
            }
            self.ticks.pop_front();
            let end = self
                .ticks
                .front()
                .map_or(self.latest_end(), |&(_, first)| first);
            let gone = (end - self.base) as usize;
            self.headers.drain(..gone);
            self.msgs.drain(..gone);
            self.base = end;
        }
        // Group by sender (a stable counting sort; in-process the messages come in robot order
        // already, and then the order is the identity). A sender id beyond the robots cannot be
        // linked by anyone: such a message is not posted.
        let n = self.by_sender.len() - 1;
        self.by_sender.fill(0);
        for (h, _) in &air.headers {
            if (h.sender as usize) < n {
                self.by_sender[h.sender as usize + 1] += 1;
            }
        }
        for r in 0..n {
            self.by_sender[r + 1] += self.by_sender[r];
        }
        self.order.clear();
        self.order.resize(self.by_sender[n] as usize, 0);
        self.next.clear();
        self.next.extend_from_slice(&self.by_sender[..n]);
        for (i, (h, _)) in air.headers.iter().enumerate() {
            if let Some(slot) = self.next.get_mut(h.sender as usize) {
                self.order[*slot as usize] = i as u32;
                *slot += 1;
            }
        }
        self.latest_first = self.latest_end();
        self.ticks.push_back((tick, self.latest_first));
        let shared: Option<Arc<dyn AsBytes>> = self
            .zero_copy
            .then(|| Arc::new(air.bytes.clone()) as Arc<dyn AsBytes>);
        for &i in &self.order {
            let (h, at) = &air.headers[i as usize];
            let msg = match &shared {
                Some(owner) => decode_in::<M>(h, owner, *at),
                None => decode::<M>(h, &air.bytes[*at..]),
            };
            self.headers.push_back(*h);
            self.msgs.push_back(msg.map(|msg| Received::new(h, msg)));
        }
    }
}

impl<M> Mailbox<M> {
    fn latest_end(&self) -> u64 {
        self.base + self.headers.len() as u64
    }

    /// The tick of the latest messages posted, if any.
    pub fn latest_tick(&self) -> Option<u64> {
        self.ticks.back().map(|&(t, _)| t)
    }

    /// The latest tick's messages from `sender` in the order sent: (index, header, whether it
    /// decoded).
    pub fn latest_from(&self, sender: u32) -> impl Iterator<Item = (u64, &RadioHeader, bool)> + '_ {
        let r = sender as usize;
        let range = if self.ticks.is_empty() || r + 1 >= self.by_sender.len() {
            0..0
        } else {
            self.by_sender[r] as u64..self.by_sender[r + 1] as u64
        };
        range.map(move |k| {
            let i = self.latest_first + k;
            let at = (i - self.base) as usize;
            (i, &self.headers[at], self.msgs[at].is_some())
        })
    }

    /// The decoded message with index `i`, if still kept and not malformed.
    pub fn get(&self, i: u64) -> Option<&Received<M>> {
        let k = i.checked_sub(self.base)? as usize;
        self.msgs.get(k)?.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::behaviour::encode;

    fn send(air: &mut Air, sender: u32, tick: u64, seq: u32, msg: u64) {
        let len = encode(&msg).len() as u32;
        let h = RadioHeader {
            sender,
            tick,
            seq,
            len,
            ..Default::default()
        };
        air.transmit(&h, &mut |buf| buf.copy_from_slice(&encode(&msg)));
    }

    #[test]
    fn groups_by_sender_keeps_order_and_forgets_what_cannot_be_due() {
        let mut mb: Mailbox<u64> = Mailbox::new(4, 1);
        let mut air = Air::default();
        send(&mut air, 2, 0, 1, 20);
        send(&mut air, 0, 0, 1, 0);
        send(&mut air, 2, 0, 2, 21);
        mb.post(0, &air);
        let from2: Vec<u64> = mb
            .latest_from(2)
            .map(|(i, _, _)| mb.get(i).unwrap().msg)
            .collect();
        assert_eq!(from2, vec![20, 21]);
        assert_eq!(mb.latest_from(1).count(), 0);
        let (i0, _, _) = mb.latest_from(0).next().unwrap();
        air.clear();
        send(&mut air, 1, 1, 1, 10);
        mb.post(1, &air);
        // Delay 1: tick 0's messages can still be due at tick 2.
        assert_eq!(mb.get(i0).unwrap().msg, 0);
        assert_eq!(mb.latest_tick(), Some(1));
        air.clear();
        mb.post(2, &air);
        assert!(mb.get(i0).is_none());
        assert_eq!(mb.latest_from(1).count(), 0);
    }

    #[test]
    fn zero_copy_blobs_are_views_into_one_shared_copy_of_the_tick() {
        use crate::blob::Blob;
        for on in [false, true] {
            let mut mb: Mailbox<(u32, Blob)> = Mailbox::new(3, 0).zero_copy(on);
            let mut air = Air::default();
            for sender in 0..3u32 {
                let msg = (sender, Blob::from(vec![sender as u8; 100]));
                let bytes = encode(&msg);
                let h = RadioHeader {
                    sender,
                    len: bytes.len() as u32,
                    ..Default::default()
                };
                air.transmit(&h, &mut |buf| buf.copy_from_slice(&bytes));
            }
            mb.post(0, &air);
            let got: Vec<&(u32, Blob)> = (0..3)
                .map(|s| {
                    let (i, _, _) = mb.latest_from(s).next().unwrap();
                    &mb.get(i).unwrap().msg
                })
                .collect();
            for (s, m) in got.iter().enumerate() {
                assert_eq!(m.0, s as u32);
                assert_eq!(&m.1[..], &[s as u8; 100][..]);
                assert_eq!(m.1.is_view(), on);
            }
            if on {
                // One copy of the tick's bytes: the views lie in it, in order, and not in Air.
                let (a, b) = (got[0].1.as_ptr() as usize, got[1].1.as_ptr() as usize);
                assert!(b > a && b - a < air.bytes.len());
                assert!(!air.bytes.as_ptr_range().contains(&got[0].1.as_ptr()));
            }
        }
    }

    #[test]
    fn a_malformed_payload_is_kept_as_none() {
        let mut mb: Mailbox<u64> = Mailbox::new(2, 0);
        let mut air = Air::default();
        let h = RadioHeader {
            sender: 1,
            len: 9,
            ..Default::default()
        };
        air.transmit(&h, &mut |buf| buf.fill(0xff));
        mb.post(0, &air);
        let (i, h, decoded) = mb.latest_from(1).next().unwrap();
        assert!(h.sender == 1 && !decoded && mb.get(i).is_none());
    }
}
