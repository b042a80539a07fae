//! The radio as one shared medium, on the wire (DESIGN 4-5; issue "The radio as one shared
//! medium").
//!
//! - **Up: the act sample.** A robot's messages of tick k travel to the world behind its
//!   Action (the act service's user header): `[RadioHeader][payload, padded to 8]` each, in
//!   send order, `Action::radio_bytes` bytes in all ([`ActTx`] writes them, [`act_messages`]
//!   reads them).
//! - **Down: the air.** The world decides every (message, receiver) pair (`world::medium`) and
//!   publishes, once a tick, one sample of the `radio/air` service that every agent reads: the
//!   messages due at the tick once each, and per receiver the indices of those that reach it
//!   ([`TickAir`], laid out by [`write_air`], read in place by [`AirView`]):
//!   `[start: robots + 1 u32][index: u32 ...][pad to 8][entries: AirEntry ...][payloads]`.
//!   Receiver r's messages are `index[start[r]..start[r + 1]]`, in (sender, seq) order.

use crate::frames::{AirEntry, AirHeader, RadioHeader};
use crate::wire::RadioTx;
use std::ops::Range;

const HEADER: usize = std::mem::size_of::<RadioHeader>();
const ENTRY: usize = std::mem::size_of::<AirEntry>();

/// `n` rounded up to a multiple of 8.
pub fn pad8(n: usize) -> usize {
    n.div_ceil(8) * 8
}

/// Bytes one message takes in an act sample: its header and its payload padded to 8.
pub fn act_entry_bytes(len: usize) -> usize {
    HEADER + pad8(len)
}

/// The largest act sample's message area: `max_messages` messages of `max_bytes` each.
pub fn act_bytes(max_messages: u32, max_bytes: u32) -> usize {
    max_messages as usize * act_entry_bytes(max_bytes as usize)
}

/// Writes a robot's messages into its act sample's message area, in send order.
pub struct ActTx<'a> {
    pub buf: &'a mut [u8],
    /// Bytes written so far.
    pub used: usize,
    /// Messages that did not fit (never with the runtime's limits; counted, not fatal).
    pub failures: u64,
}

impl<'a> ActTx<'a> {
    pub fn new(buf: &'a mut [u8]) -> ActTx<'a> {
        ActTx {
            buf,
            used: 0,
            failures: 0,
        }
    }
}

impl RadioTx for ActTx<'_> {
    fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
        let len = h.len as usize;
        let end = self.used + act_entry_bytes(len);
        if end > self.buf.len() {
            self.failures += 1;
            return;
        }
        let at = self.used;
        // SAFETY: RadioHeader is repr(C) plain old data; the range was checked above.
        let bytes =
            unsafe { std::slice::from_raw_parts(h as *const RadioHeader as *const u8, HEADER) };
        self.buf[at..at + HEADER].copy_from_slice(bytes);
        fill(&mut self.buf[at + HEADER..at + HEADER + len]);
        self.used = end;
    }
}

/// Reads a header out of `bytes` at `at` (any alignment).
fn read_header(bytes: &[u8], at: usize) -> Option<RadioHeader> {
    let b = bytes.get(at..at + HEADER)?;
    // SAFETY: HEADER bytes are there; every bit pattern is a valid RadioHeader.
    Some(unsafe { std::ptr::read_unaligned(b.as_ptr() as *const RadioHeader) })
}

/// The messages of an act sample's message area (`bytes`, the first `Action::radio_bytes`):
/// (header, payload) in send order, or None if the area is malformed (a header or payload
/// past its end).
pub fn act_messages(bytes: &[u8]) -> Option<Vec<(RadioHeader, &[u8])>> {
    let mut out = Vec::new();
    for_each_act_message(bytes, |h, p| out.push((*h, p))).then_some(out)
}

/// [`act_messages`] without its list: calls `each` with every (header, payload) of a
/// well-formed area in send order and returns true; a malformed area calls it for none and
/// returns false. The world's tick path (no allocation a robot a tick).
pub fn for_each_act_message<'a>(
    bytes: &'a [u8],
    mut each: impl FnMut(&RadioHeader, &'a [u8]),
) -> bool {
    let walk = |each: &mut dyn FnMut(&RadioHeader, &'a [u8])| -> Option<()> {
        let mut at = 0;
        while at < bytes.len() {
            let h = read_header(bytes, at)?;
            let len = h.len as usize;
            let p = bytes.get(at + HEADER..at + HEADER + len)?;
            each(&h, p);
            at = at.checked_add(act_entry_bytes(len))?;
        }
        Some(())
    };
    // First pass: the whole area parses; second: hand out its messages.
    if walk(&mut |_, _| {}).is_none() {
        return false;
    }
    walk(&mut each).is_some()
}

/// One tick's transmissions as the air carries them: built by the world's medium, published
/// as one sample (multi-process) or read in memory (in-process).
#[derive(Debug, Default, Clone, PartialEq)]
pub struct TickAir {
    /// The send tick.
    pub tick: u64,
    /// Every message sent at the tick that reaches someone, in (sender, seq) order, with its
    /// payload's range in `bytes` (in the sender's buffer when `lent`).
    pub messages: Vec<(RadioHeader, Range<usize>)>,
    pub bytes: Vec<u8>,
    /// The payloads were not copied into `bytes`: the ranges index the buffer the messages
    /// were sent in, which its owner writes into the air itself ([`write_air_from`];
    /// `world::medium::Medium::transmit_lent`).
    pub lent: bool,
    /// Receiver r's messages are `index[start[r]..start[r + 1]]` (indices into `messages`).
    pub start: Vec<u32>,
    pub index: Vec<u32>,
    /// Payload bytes of receiver r's list (the radio's byte counters; not on the wire).
    pub bytes_to: Vec<u64>,
}

impl TickAir {
    /// Empties it, keeping its allocations.
    pub fn clear(&mut self) {
        self.tick = 0;
        self.lent = false;
        self.messages.clear();
        self.bytes.clear();
        self.start.clear();
        self.index.clear();
        self.bytes_to.clear();
    }
    /// Payload bytes of the messages that reach `robot`.
    pub fn bytes_to(&self, robot: u32) -> u64 {
        self.bytes_to.get(robot as usize).copied().unwrap_or(0)
    }
    /// The messages that reach `robot`.
    pub fn deliveries(&self, robot: u32) -> &[u32] {
        let r = robot as usize;
        match (self.start.get(r), self.start.get(r + 1)) {
            (Some(&a), Some(&b)) => &self.index[a as usize..b as usize],
            _ => &[],
        }
    }
    /// Message `i`'s header and payload (not of a `lent` air: its payloads are elsewhere).
    pub fn message(&self, i: u32) -> Option<(&RadioHeader, &[u8])> {
        debug_assert!(
            !self.lent,
            "a lent air's payloads are in its sender's buffer"
        );
        let (h, r) = self.messages.get(i as usize)?;
        Some((h, self.bytes.get(r.clone())?))
    }
    /// Payload bytes of its messages, back to back as the air sample carries them.
    pub fn payload_len(&self) -> usize {
        self.messages.iter().map(|(_, r)| r.len()).sum()
    }
    /// (message, receiver) pairs it carries.
    pub fn pairs(&self) -> u64 {
        self.index.len() as u64
    }
    /// Receivers it has lists for (0 for an empty air).
    pub fn robots(&self) -> usize {
        self.start.len().saturating_sub(1)
    }
}

/// Where the parts of an air sample lie.
#[derive(Debug, Clone, Copy)]
struct Layout {
    index: usize,
    entries: usize,
    payloads: usize,
    end: usize,
}

fn layout(robots: usize, index_len: usize, messages: usize, payload_bytes: usize) -> Layout {
    let index = 4 * (robots + 1);
    let entries = pad8(index + 4 * index_len);
    let payloads = entries + ENTRY * messages;
    Layout {
        index,
        entries,
        payloads,
        end: payloads + payload_bytes,
    }
}

/// Bytes of `air`'s sample for a run of `robots` robots.
pub fn air_len(air: Option<&TickAir>, robots: usize) -> usize {
    match air {
        Some(a) => layout(robots, a.index.len(), a.messages.len(), a.payload_len()).end,
        None => layout(robots, 0, 0, 0).end,
    }
}

/// Bytes of the largest air a tick of `robots` agents can make, each sending `max_messages`
/// messages of `max_bytes`, every message reaching every agent (its sender too: an upper
/// bound). The air service's slots are this size.
pub fn air_max_len(robots: usize, max_messages: usize, max_bytes: usize) -> usize {
    let messages = robots * max_messages;
    layout(robots, messages * robots, messages, messages * max_bytes).end
}

/// Writes `air` (None: nothing due) into an air sample's payload `out` (at least
/// [`air_len`] bytes) and returns its header. `due` is the tick it is due at. The air must
/// hold its payloads (not `lent`: see [`write_air_from`]).
pub fn write_air(air: Option<&TickAir>, robots: usize, due: u64, out: &mut [u8]) -> AirHeader {
    assert!(
        air.is_none_or(|a| !a.lent),
        "a lent air is written with write_air_from"
    );
    write_air_from(air, &[], robots, due, out)
}

/// [`write_air`] of an air whose payloads may be `lent` (`Medium::transmit_lent`): then its
/// message ranges index `sent`, the buffer its messages were sent in, and each payload is
/// copied from there straight into `out` (the medium copied none). An air that holds its
/// payloads ignores `sent`. Either way the sample's bytes are the same.
pub fn write_air_from(
    air: Option<&TickAir>,
    sent: &[u8],
    robots: usize,
    due: u64,
    out: &mut [u8],
) -> AirHeader {
    let empty = TickAir::default();
    let a = air.unwrap_or(&empty);
    let src: &[u8] = if a.lent { sent } else { &a.bytes };
    let payload_len = a.payload_len();
    let l = layout(robots, a.index.len(), a.messages.len(), payload_len);
    assert!(out.len() >= l.end, "air sample too small");
    for r in 0..=robots {
        let v = a.start.get(r).copied().unwrap_or(a.index.len() as u32);
        out[4 * r..4 * r + 4].copy_from_slice(&v.to_ne_bytes());
    }
    for (k, v) in a.index.iter().enumerate() {
        let at = l.index + 4 * k;
        out[at..at + 4].copy_from_slice(&v.to_ne_bytes());
    }
    out[l.index + 4 * a.index.len()..l.entries].fill(0);
    // Payloads back to back in message order: for an air that holds them this is `bytes`
    // itself (the medium appends them in that order).
    let mut offset = 0;
    for (k, (h, range)) in a.messages.iter().enumerate() {
        let e = AirEntry {
            header: *h,
            offset: offset as u32,
            reserved: 0,
        };
        let at = l.entries + ENTRY * k;
        // SAFETY: AirEntry is repr(C) plain old data without padding.
        let bytes =
            unsafe { std::slice::from_raw_parts(&e as *const AirEntry as *const u8, ENTRY) };
        out[at..at + ENTRY].copy_from_slice(bytes);
        let p = l.payloads + offset;
        out[p..p + range.len()].copy_from_slice(&src[range.clone()]);
        offset += range.len();
    }
    AirHeader {
        tick: due,
        sent_tick: a.tick,
        robots: robots as u32,
        messages: a.messages.len() as u32,
        index_len: a.index.len() as u32,
        payload_bytes: payload_len as u32,
    }
}

/// An air sample read in place.
pub struct AirView<'a> {
    bytes: &'a [u8],
    robots: usize,
    l: Layout,
    messages: usize,
}

impl<'a> AirView<'a> {
    /// The view of a sample's payload with its header; None if they do not agree.
    pub fn new(h: &AirHeader, bytes: &'a [u8]) -> Option<AirView<'a>> {
        let robots = h.robots as usize;
        let l = layout(
            robots,
            h.index_len as usize,
            h.messages as usize,
            h.payload_bytes as usize,
        );
        (bytes.len() >= l.end).then_some(AirView {
            bytes,
            robots,
            l,
            messages: h.messages as usize,
        })
    }

    fn u32_at(&self, at: usize) -> u32 {
        u32::from_ne_bytes(self.bytes[at..at + 4].try_into().expect("4 bytes"))
    }

    /// The indices of the messages that reach `robot`.
    pub fn deliveries(&self, robot: u32) -> impl Iterator<Item = u32> + '_ {
        let r = robot as usize;
        let (a, b) = if r < self.robots {
            (self.u32_at(4 * r) as usize, self.u32_at(4 * r + 4) as usize)
        } else {
            (0, 0)
        };
        let b = b.min((self.l.entries - self.l.index) / 4);
        (a.min(b)..b).map(move |k| self.u32_at(self.l.index + 4 * k))
    }

    /// Message `i`: its header and the offset of its payload in the sample's bytes (None if
    /// `i` or the payload lies outside the sample).
    pub fn message(&self, i: u32) -> Option<(RadioHeader, usize)> {
        let i = i as usize;
        if i >= self.messages {
            return None;
        }
        let at = self.l.entries + ENTRY * i;
        let b = self.bytes.get(at..at + ENTRY)?;
        // SAFETY: ENTRY bytes are there; every bit pattern is a valid AirEntry.
        let e = unsafe { std::ptr::read_unaligned(b.as_ptr() as *const AirEntry) };
        let from = self.l.payloads.checked_add(e.offset as usize)?;
        (from.checked_add(e.header.len as usize)? <= self.l.end).then_some((e.header, from))
    }

    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::BROADCAST;

    fn header(sender: u32, seq: u32, len: u32) -> RadioHeader {
        RadioHeader {
            sender,
            dest: BROADCAST,
            tick: 3,
            seq,
            len,
            sender_pos: [sender as f64, 1.0],
        }
    }

    #[test]
    fn act_messages_read_back_what_act_tx_wrote() {
        let mut buf = vec![0xaa; act_bytes(3, 20)];
        let mut tx = ActTx::new(&mut buf);
        for (seq, len) in [(1u32, 5u32), (2, 0), (3, 20)] {
            tx.transmit(&header(4, seq, len), &mut |b| b.fill(seq as u8));
        }
        assert_eq!(tx.failures, 0);
        let used = tx.used;
        // 5 bytes pad to 8, 0 bytes to 0, 20 bytes to 24, each behind a 40-byte header.
        assert_eq!(used, 40 + 8 + 40 + 40 + 24);
        let got = act_messages(&buf[..used]).unwrap();
        assert_eq!(got.len(), 3);
        for (k, (h, p)) in got.iter().enumerate() {
            assert_eq!(h.seq, k as u32 + 1);
            assert!(p.iter().all(|&b| b == h.seq as u8) && p.len() == h.len as usize);
        }
        // A header claiming more bytes than there are: malformed.
        assert!(act_messages(&buf[..used - 5]).is_none());
        // One more message than the area holds: refused, counted.
        let mut small = vec![0; act_bytes(1, 8)];
        let mut tx = ActTx::new(&mut small);
        tx.transmit(&header(0, 1, 8), &mut |b| b.fill(1));
        tx.transmit(&header(0, 2, 8), &mut |b| b.fill(1));
        assert_eq!((tx.failures, tx.used), (1, 48));
    }

    #[test]
    fn an_air_sample_reads_back_in_place_as_written() {
        let mut air = TickAir {
            tick: 9,
            ..Default::default()
        };
        for (s, len) in [(0u32, 3usize), (2, 0), (2, 11)] {
            let at = air.bytes.len();
            air.bytes.extend(std::iter::repeat_n(s as u8 + 1, len));
            air.messages.push((
                header(s, air.messages.len() as u32, len as u32),
                at..at + len,
            ));
        }
        // Robots 0..4: robot 1 hears all three, robot 3 the last one, the others nothing.
        air.start = vec![0, 0, 3, 3, 4];
        air.index = vec![0, 1, 2, 2];
        let mut out = vec![0xee; air_len(Some(&air), 4)];
        let h = write_air(Some(&air), 4, 10, &mut out);
        assert_eq!(
            (h.tick, h.sent_tick, h.messages, h.index_len),
            (10, 9, 3, 4)
        );
        let v = AirView::new(&h, &out).unwrap();
        for r in 0..5u32 {
            let want: Vec<u32> = air.deliveries(r).to_vec();
            assert_eq!(v.deliveries(r).collect::<Vec<_>>(), want, "robot {r}");
        }
        for i in 0..3u32 {
            let (hh, at) = v.message(i).unwrap();
            let (wh, wp) = air.message(i).unwrap();
            assert_eq!(&hh, wh);
            assert_eq!(&out[at..at + hh.len as usize], wp);
        }
        assert!(v.message(3).is_none());
        // An empty air: every robot's list empty.
        let mut out = vec![0; air_len(None, 4)];
        let h = write_air(None, 4, 1, &mut out);
        let v = AirView::new(&h, &out).unwrap();
        assert!((0..4).all(|r| v.deliveries(r).count() == 0));
        // A header that claims more than the sample holds: no view.
        let bad = AirHeader {
            payload_bytes: 1000,
            ..h
        };
        assert!(AirView::new(&bad, &out).is_none());
    }

    /// A lent air (payload ranges into the sender's buffer, some of it not sent on) writes
    /// the same sample bytes as the same air holding its payloads.
    #[test]
    fn a_lent_air_writes_the_same_sample_as_one_holding_its_payloads() {
        let sent: Vec<u8> = (0..64u8).collect();
        // Messages at 5..8, 20..20 and 30..41 of the sender's buffer; the rest reached nobody.
        let ranges = [5..8usize, 20..20, 30..41];
        let mut lent = TickAir {
            tick: 9,
            lent: true,
            ..Default::default()
        };
        let mut owned = TickAir {
            tick: 9,
            ..Default::default()
        };
        for (k, r) in ranges.iter().enumerate() {
            let h = header(k as u32, k as u32, r.len() as u32);
            lent.messages.push((h, r.clone()));
            let at = owned.bytes.len();
            owned.bytes.extend_from_slice(&sent[r.clone()]);
            owned.messages.push((h, at..owned.bytes.len()));
        }
        for a in [&mut lent, &mut owned] {
            a.start = vec![0, 2, 3, 3];
            a.index = vec![0, 2, 1];
        }
        assert_eq!(air_len(Some(&lent), 3), air_len(Some(&owned), 3));
        let mut a = vec![0xee; air_len(Some(&owned), 3)];
        let mut b = vec![0x11; a.len()];
        let ha = write_air(Some(&owned), 3, 10, &mut a);
        let hb = write_air_from(Some(&lent), &sent, 3, 10, &mut b);
        assert_eq!(ha, hb);
        assert_eq!(a, b);
        let v = AirView::new(&hb, &b).unwrap();
        let (h, at) = v.message(2).unwrap();
        assert_eq!(&b[at..at + h.len as usize], &sent[30..41]);
    }

    #[test]
    #[should_panic(expected = "write_air_from")]
    fn a_lent_air_is_not_written_without_its_buffer() {
        let air = TickAir {
            lent: true,
            ..Default::default()
        };
        let mut out = vec![0; air_len(Some(&air), 1)];
        write_air(Some(&air), 1, 1, &mut out);
    }
}
