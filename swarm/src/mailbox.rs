//! The in-process executor's radio: what iceoryx2 carries between processes, carried in memory.
//!
//! Senders encode their messages into an [`Air`] as the agent process writes them behind its
//! Action; the world's medium decides who hears what and hands back the tick's
//! [`TickAir`] when it is due. The [`Mailbox`] decodes each of its messages once; each
//! receiver's inbox is references into it, by the air's index (at N = 100 a message has ~50
//! receivers: decoding, cloning and dropping it once per receiver was most of the in-process
//! radio's cost).

use crate::air::TickAir;
use crate::behaviour::{decode, decode_in, RadioTx, Received};
use crate::blob::AsBytes;
use crate::frames::RadioHeader;
use serde::de::DeserializeOwned;
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

    /// The messages in the order sent: header and the offset of its payload in [`Air::bytes`].
    pub fn entries(&self) -> &[(RadioHeader, usize)] {
        &self.headers
    }

    /// Every payload, back to back.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
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

    /// Drops every message after the first `len` (those of a sender found faulty after they
    /// were appended).
    pub fn truncate(&mut self, len: usize) {
        if let Some(&(_, at)) = self.headers.get(len) {
            self.bytes.truncate(at);
        }
        self.headers.truncate(len);
    }

    pub fn is_empty(&self) -> bool {
        self.headers.is_empty()
    }
}

/// The messages due at a tick, decoded once for all their receivers.
pub struct Mailbox<M> {
    /// Decoded messages of the air (None: malformed), by the air's message index.
    msgs: Vec<Option<Received<M>>>,
    /// Receiver r's messages are `index[start[r]..start[r + 1]]`.
    start: Vec<u32>,
    index: Vec<u32>,
    /// Decode each tick's messages in a shared copy of its bytes, so that their Blob fields are
    /// views into it (the behaviour's `zero_copy()`).
    zero_copy: bool,
}

impl<M: DeserializeOwned> Default for Mailbox<M> {
    fn default() -> Self {
        Mailbox::new()
    }
}

impl<M: DeserializeOwned> Mailbox<M> {
    pub fn new() -> Mailbox<M> {
        Mailbox {
            msgs: Vec::new(),
            start: Vec::new(),
            index: Vec::new(),
            zero_copy: false,
        }
    }

    /// Zero-copy receive (see [`crate::Behaviour::zero_copy`]): each tick's bytes are copied
    /// once into a shared buffer, and every receiver's Blob fields are views into it.
    pub fn zero_copy(mut self, on: bool) -> Mailbox<M> {
        self.zero_copy = on;
        self
    }

    /// Posts the messages due at this tick (None: nothing is), decoding each once. The air
    /// holds its payloads (the world's `Medium::transmit`, not a `lent` air).
    pub fn post(&mut self, air: Option<&TickAir>) {
        self.msgs.clear();
        self.start.clear();
        self.index.clear();
        let Some(air) = air else {
            return;
        };
        assert!(!air.lent, "a lent air's payloads are not in it");
        let shared: Option<Arc<dyn AsBytes>> = self
            .zero_copy
            .then(|| Arc::new(air.bytes.clone()) as Arc<dyn AsBytes>);
        for (h, range) in &air.messages {
            let msg = match &shared {
                Some(owner) => decode_in::<M>(h, owner, range.start),
                None => decode::<M>(h, &air.bytes[range.clone()]),
            };
            self.msgs.push(msg.map(|m| Received::new(h, m)));
        }
        self.start.extend_from_slice(&air.start);
        self.index.extend_from_slice(&air.index);
    }
}

impl<M> Mailbox<M> {
    /// Robot `robot`'s inbox (appended to `inbox`, in (sender, seq) order) and how many of
    /// its messages were malformed.
    pub fn inbox<'a>(&'a self, robot: u32, inbox: &mut Vec<&'a Received<M>>) -> u32 {
        let r = robot as usize;
        let (Some(&a), Some(&b)) = (self.start.get(r), self.start.get(r + 1)) else {
            return 0;
        };
        let mut malformed = 0;
        for &i in &self.index[a as usize..b as usize] {
            match self.msgs.get(i as usize).and_then(|m| m.as_ref()) {
                Some(m) => inbox.push(m),
                None => malformed += 1,
            }
        }
        malformed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::behaviour::encode;

    /// An air whose messages are `msgs` (sender, payload bytes), every robot of `robots`
    /// hearing the messages listed for it.
    fn air(msgs: &[(u32, Vec<u8>)], lists: &[Vec<u32>]) -> TickAir {
        let mut a = TickAir::default();
        for (k, (s, b)) in msgs.iter().enumerate() {
            let at = a.bytes.len();
            a.bytes.extend_from_slice(b);
            let h = RadioHeader {
                sender: *s,
                seq: k as u32,
                len: b.len() as u32,
                ..Default::default()
            };
            a.messages.push((h, at..at + b.len()));
        }
        a.start.push(0);
        for l in lists {
            a.index.extend_from_slice(l);
            a.start.push(a.index.len() as u32);
        }
        a
    }

    #[test]
    fn each_receiver_gets_its_listed_messages_decoded_once() {
        let mut mb: Mailbox<u64> = Mailbox::new();
        let a = air(
            &[(0, encode(&7u64)), (2, encode(&9u64)), (2, vec![0xff; 9])],
            &[vec![1, 2], vec![], vec![0]],
        );
        mb.post(Some(&a));
        let mut got = Vec::new();
        assert_eq!(mb.inbox(0, &mut got), 1, "the garbage payload is malformed");
        assert_eq!(
            got.iter().map(|r| (r.from, r.msg)).collect::<Vec<_>>(),
            vec![(2, 9)]
        );
        let mut got2 = Vec::new();
        assert_eq!(mb.inbox(2, &mut got2), 0);
        assert_eq!(got2[0].msg, 7);
        // One decoded copy: two receivers of one message hold the same reference.
        let b = air(&[(0, encode(&7u64))], &[vec![], vec![0], vec![0]]);
        mb.post(Some(&b));
        let (mut x, mut y) = (Vec::new(), Vec::new());
        mb.inbox(1, &mut x);
        mb.inbox(2, &mut y);
        assert!(std::ptr::eq(x[0], y[0]));
        assert_eq!(mb.inbox(7, &mut x), 0);
        mb.post(None);
        let mut z = Vec::new();
        mb.inbox(1, &mut z);
        assert!(z.is_empty());
    }

    #[test]
    fn zero_copy_blobs_are_views_into_one_shared_copy_of_the_tick() {
        use crate::blob::Blob;
        for on in [false, true] {
            let mut mb: Mailbox<(u32, Blob)> = Mailbox::new().zero_copy(on);
            let msgs: Vec<(u32, Vec<u8>)> = (0..3u32)
                .map(|s| (s, encode(&(s, Blob::from(vec![s as u8; 100])))))
                .collect();
            let a = air(&msgs, &[vec![0, 1, 2]]);
            mb.post(Some(&a));
            let mut got = Vec::new();
            mb.inbox(0, &mut got);
            for (s, m) in got.iter().enumerate() {
                assert_eq!(m.msg.0, s as u32);
                assert_eq!(&m.msg.1[..], &[s as u8; 100][..]);
                assert_eq!(m.msg.1.is_view(), on);
            }
            if on {
                // One copy of the tick's bytes: the views lie in it, in order, and not in the air.
                let (p, q) = (
                    got[0].msg.1.as_ptr() as usize,
                    got[1].msg.1.as_ptr() as usize,
                );
                assert!(q > p && q - p < a.bytes.len());
                assert!(!a.bytes.as_ptr_range().contains(&got[0].msg.1.as_ptr()));
            }
        }
    }
}
