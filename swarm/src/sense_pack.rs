//! Every robot's Sense frame of a tick, packed into one sample of the `world/sense` service
//! (`swarm::transport::SenseSink`). With one iceoryx2 service per robot the world made N
//! publishes and the agents N receives a tick, each a handful of iceoryx2 port operations
//! (BENCHMARKS 11); here the world packs every live robot's frame into one buffer and
//! publishes it once; each agent copies its own record into its frame (the used part only:
//! the fixed fields and the lists up to their counts, a few hundred bytes for most robots,
//! where a whole frame is 14,920).
//!
//! # Layout
//!
//! `[robots: u32][reserved: u32]`, then `robots` index entries `[offset: u32][len: u32]`
//! (len 0: no frame for that robot this tick, e.g. dead), then the records, each 8-byte
//! aligned: the frame's first [`SENSE_FIXED_BYTES`] bytes, then its obstacle points, entities
//! and nearby robots up to their counts, as they lie in the frame (plain old data).
//! A reader checks every offset, length and count against the buffer and the frame's limits:
//! a record that does not fit is refused ([`SenseFrameError`]), never read out of bounds.

use crate::frames::{
    Entity, Nearby, Sense, MAX_ENTITIES, MAX_NEARBY, MAX_OBSTACLE_POINTS, SENSE_FIXED_BYTES,
};
use std::mem::{offset_of, size_of};

/// Bytes before the index.
const HEAD: usize = 8;
/// Bytes of one index entry.
const ENTRY: usize = 8;
const POINT: usize = size_of::<[f64; 2]>();
const ENTITY: usize = size_of::<Entity>();
const NEARBY: usize = size_of::<Nearby>();

/// Why a robot's record could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SenseFrameError {
    #[error("the sense buffer of {len} bytes is shorter than its index")]
    Short { len: usize },
    #[error("robot {robot} is not in the sense buffer (robots 0..{robots})")]
    NoRobot { robot: u32, robots: u32 },
    #[error("robot {robot}'s sense record ({offset}+{len}) lies outside the buffer ({bytes} bytes) or does not match its counts")]
    Bad {
        robot: u32,
        offset: usize,
        len: usize,
        bytes: usize,
    },
}

fn frame_bytes(s: &Sense) -> &[u8] {
    // SAFETY: Sense is repr(C) plain old data without padding (frames.rs tests its size
    // against its fields'): every byte is initialised.
    unsafe { std::slice::from_raw_parts(s as *const Sense as *const u8, size_of::<Sense>()) }
}

fn frame_bytes_mut(s: &mut Sense) -> &mut [u8] {
    // SAFETY: as above; any bytes are a valid Sense (integers and floats only).
    unsafe { std::slice::from_raw_parts_mut(s as *mut Sense as *mut u8, size_of::<Sense>()) }
}

/// The parts of a frame a record carries: (offset in the frame, bytes), in record order.
fn parts(points: usize, entities: usize, nearby: usize) -> [(usize, usize); 4] {
    [
        (0, SENSE_FIXED_BYTES),
        (offset_of!(Sense, obstacle_points), points * POINT),
        (offset_of!(Sense, entities), entities * ENTITY),
        (offset_of!(Sense, nearby), nearby * NEARBY),
    ]
}

fn counts(s: &Sense) -> (usize, usize, usize) {
    (
        (s.n_obstacle_points as usize).min(MAX_OBSTACLE_POINTS),
        (s.n_entities as usize).min(MAX_ENTITIES),
        (s.n_nearby as usize).min(MAX_NEARBY),
    )
}

/// Bytes of the largest record: a whole frame, every list full.
const MAX_RECORD: usize =
    SENSE_FIXED_BYTES + MAX_OBSTACLE_POINTS * POINT + MAX_ENTITIES * ENTITY + MAX_NEARBY * NEARBY;

/// Bytes of the largest packed tick of `robots` robots: the index, and every robot's record
/// with every list full, each 8-byte aligned.
pub fn max_len(robots: u32) -> usize {
    HEAD + robots as usize * (ENTRY + MAX_RECORD.next_multiple_of(8))
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_ne_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_ne_bytes());
}

/// The world's side: packs a tick's frames (reused from tick to tick, no allocation once
/// grown).
#[derive(Default)]
pub struct SensePacker {
    buf: Vec<u8>,
    robots: u32,
}

impl SensePacker {
    /// Starts a tick's buffer for `robots` robots, every one without a frame yet.
    pub fn begin(&mut self, robots: u32) {
        self.robots = robots;
        self.buf.clear();
        self.buf.resize(HEAD + robots as usize * ENTRY, 0);
        put_u32(&mut self.buf, 0, robots);
    }

    /// Appends robot `robot`'s frame (the lists up to their counts, capped at the frame's
    /// limits). A robot outside `begin`'s range is ignored.
    pub fn push(&mut self, robot: u32, s: &Sense) {
        if robot >= self.robots {
            return;
        }
        let at = self.buf.len().next_multiple_of(8);
        self.buf.resize(at, 0);
        let (p, e, n) = counts(s);
        let src = frame_bytes(s);
        for (from, len) in parts(p, e, n) {
            self.buf.extend_from_slice(&src[from..from + len]);
        }
        let len = self.buf.len() - at;
        let entry = HEAD + robot as usize * ENTRY;
        put_u32(&mut self.buf, entry, at as u32);
        put_u32(&mut self.buf, entry + 4, len as u32);
        // The record's counts are the capped ones its lists were cut to.
        let counts_at = offset_of!(Sense, n_obstacle_points);
        put_u32(&mut self.buf, at + counts_at, p as u32);
        put_u32(&mut self.buf, at + offset_of!(Sense, n_entities), e as u32);
        put_u32(&mut self.buf, at + offset_of!(Sense, n_nearby), n as u32);
    }

    /// The packed tick.
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }
}

/// Reads robot `robot`'s record of the packed `bytes` into `out`: its fixed fields and its
/// lists up to their counts (what lies beyond the counts in `out` is left as it was, as in a
/// reused iceoryx2 sample). `Ok(false)`: no frame for the robot in this buffer.
pub fn unpack_into(bytes: &[u8], robot: u32, out: &mut Sense) -> Result<bool, SenseFrameError> {
    if bytes.len() < HEAD {
        return Err(SenseFrameError::Short { len: bytes.len() });
    }
    let robots = u32_at(bytes, 0);
    if robot >= robots {
        return Err(SenseFrameError::NoRobot { robot, robots });
    }
    let entry = HEAD + robot as usize * ENTRY;
    if bytes.len() < HEAD + robots as usize * ENTRY {
        return Err(SenseFrameError::Short { len: bytes.len() });
    }
    let (offset, len) = (
        u32_at(bytes, entry) as usize,
        u32_at(bytes, entry + 4) as usize,
    );
    if len == 0 {
        return Ok(false);
    }
    let bad = SenseFrameError::Bad {
        robot,
        offset,
        len,
        bytes: bytes.len(),
    };
    let Some(rec) = offset
        .checked_add(len)
        .and_then(|end| bytes.get(offset..end))
    else {
        return Err(bad);
    };
    if len < SENSE_FIXED_BYTES {
        return Err(bad);
    }
    let c = |field: usize| u32_at(rec, field) as usize;
    let (p, e, n) = (
        c(offset_of!(Sense, n_obstacle_points)),
        c(offset_of!(Sense, n_entities)),
        c(offset_of!(Sense, n_nearby)),
    );
    if p > MAX_OBSTACLE_POINTS
        || e > MAX_ENTITIES
        || n > MAX_NEARBY
        || SENSE_FIXED_BYTES + p * POINT + e * ENTITY + n * NEARBY != len
    {
        return Err(bad);
    }
    let dst = frame_bytes_mut(out);
    let mut at = 0;
    for (to, l) in parts(p, e, n) {
        dst[to..to + l].copy_from_slice(&rec[at..at + l]);
        at += l;
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(robot: u32, points: usize, entities: usize, nearby: usize) -> Box<Sense> {
        let mut s = Sense::zeroed();
        s.fill_every_list(robot as f64 + 0.5);
        s.tick = 41;
        s.robot = robot;
        s.pos = [robot as f64, -1.0];
        s.n_obstacle_points = points as u32;
        s.n_entities = entities as u32;
        s.n_nearby = nearby as u32;
        s
    }

    fn used_eq(a: &Sense, b: &Sense) -> bool {
        a.tick == b.tick
            && a.robot == b.robot
            && a.pos == b.pos
            && a.heading == b.heading
            && a.vel == b.vel
            && a.alive_robots == b.alive_robots
            && a.run_state == b.run_state
            && a.obstacle_points() == b.obstacle_points()
            && a.entities() == b.entities()
            && a.nearby() == b.nearby()
    }

    #[test]
    fn frames_round_trip_and_records_are_as_long_as_their_counts() {
        let mut p = SensePacker::default();
        p.begin(4);
        let frames = [
            frame(0, 0, 0, 0),
            frame(1, 3, 1, 2),
            frame(3, MAX_OBSTACLE_POINTS, MAX_ENTITIES, MAX_NEARBY),
        ];
        for f in &frames {
            p.push(f.robot, f);
        }
        let b = p.bytes();
        // Hand-computed: head 8 + index 4 x 8 = 40; robot 0: 72 bytes at 40; robot 1: at 112,
        // 72 + 3 x 16 + 40 + 2 x 40 = 240; robot 3 at 352, a whole frame's 14,920.
        assert_eq!(u32_at(b, 8), 40);
        assert_eq!(u32_at(b, 12), 72);
        assert_eq!(u32_at(b, 16), 112);
        assert_eq!(u32_at(b, 20), 240);
        assert_eq!(u32_at(b, 24 + 4), 0, "robot 2 has no frame");
        assert_eq!(u32_at(b, 32), 352);
        assert_eq!(u32_at(b, 36) as usize, size_of::<Sense>());
        assert_eq!(b.len(), 352 + size_of::<Sense>());
        assert!(b.len() <= max_len(4));
        assert_eq!(MAX_RECORD, size_of::<Sense>());
        for f in &frames {
            let mut out = Sense::zeroed();
            assert_eq!(unpack_into(b, f.robot, &mut out), Ok(true));
            assert!(used_eq(&out, f), "robot {}", f.robot);
        }
        let mut out = Sense::zeroed();
        assert_eq!(unpack_into(b, 2, &mut out), Ok(false));
        assert_eq!(
            unpack_into(b, 4, &mut out),
            Err(SenseFrameError::NoRobot {
                robot: 4,
                robots: 4
            })
        );
    }

    #[test]
    fn counts_beyond_the_limits_are_cut_when_packed() {
        let mut p = SensePacker::default();
        p.begin(1);
        let mut f = frame(0, 5, 2, 1);
        f.n_obstacle_points = u32::MAX;
        p.push(0, &f);
        let mut out = Sense::zeroed();
        assert_eq!(unpack_into(p.bytes(), 0, &mut out), Ok(true));
        assert_eq!(out.n_obstacle_points as usize, MAX_OBSTACLE_POINTS);
        assert_eq!(out.obstacle_points(), f.obstacle_points());
    }

    /// Any corruption of the index or the counts is refused, never read out of bounds.
    #[test]
    fn corrupt_buffers_are_refused_not_read_out_of_bounds() {
        let mut p = SensePacker::default();
        p.begin(2);
        p.push(1, &frame(1, 2, 0, 1));
        let good = p.bytes().to_vec();
        let mut out = Sense::zeroed();
        let at = |b: &[u8]| unpack_into(b, 1, &mut Sense::zeroed());
        assert_eq!(unpack_into(&good, 1, &mut out), Ok(true));
        assert!(matches!(
            unpack_into(&good[..4], 1, &mut out),
            Err(SenseFrameError::Short { .. })
        ));
        assert!(matches!(
            unpack_into(&good[..20], 1, &mut out),
            Err(SenseFrameError::Short { .. })
        ));
        // Truncated record.
        assert!(matches!(
            at(&good[..good.len() - 1]),
            Err(SenseFrameError::Bad { .. })
        ));
        // Offset past the end, and an offset + len that overflows.
        for (off, len) in [(good.len() as u32, 72u32), (u32::MAX, u32::MAX)] {
            let mut b = good.clone();
            put_u32(&mut b, 16, off);
            put_u32(&mut b, 20, len);
            assert!(matches!(at(&b), Err(SenseFrameError::Bad { .. })));
        }
        // Too short for the fixed part.
        let mut b = good.clone();
        put_u32(&mut b, 20, 8);
        assert!(matches!(at(&b), Err(SenseFrameError::Bad { .. })));
        // Counts that disagree with the length, or exceed the limits.
        let rec = u32_at(&good, 16) as usize;
        for (field, v) in [
            (offset_of!(Sense, n_obstacle_points), 3),
            (offset_of!(Sense, n_nearby), MAX_NEARBY as u32 + 1),
            (offset_of!(Sense, n_entities), u32::MAX),
        ] {
            let mut b = good.clone();
            put_u32(&mut b, rec + field, v);
            assert!(matches!(at(&b), Err(SenseFrameError::Bad { .. })));
        }
        // A robot count larger than the index in the buffer.
        let mut b = good.clone();
        put_u32(&mut b, 0, 1000);
        assert!(matches!(at(&b), Err(SenseFrameError::Short { .. })));
    }
}
