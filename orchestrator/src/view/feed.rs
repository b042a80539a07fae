//! The frames of a run, shared by the page's requests: all of a finished recording at once, or
//! a live run's recording.bin followed as the world writes it.
//!
//! The follower reads the file on its own thread and never talks to the world: the world only
//! flushes each tick (`world --live`), so a page that is slow, or gone, cannot slow the run.
//! Every stream request reads the shared list from its own position; none waits for another.
//!
//! The frames' JSON is not held in memory: each is appended to an unnamed spill file (created in
//! the temp dir and unlinked at once, so nothing is left behind even on SIGKILL), and the feed
//! keeps only each frame's (offset, length). A 500-robot, 3,000-tick run's ~150 MB of JSON
//! costs the server 48 KB of index; the kernel's page cache serves the chunks the page asks
//! for again.

use super::frame::Framer;
use super::meta::{Meta, MetaError};
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;
use swarm::recording::{read_finished_header, read_header, RecordingHeader, TickReader};
#[cfg(test)]
use swarm::scenario::Scenario;

/// How often the follower looks for new bytes of a live recording.
const FOLLOW_POLL: Duration = Duration::from_millis(20);

/// About this many bytes of frame JSON make one chunk, the ticks the page asks for at a time
/// (`/api/frames?from=K&to=L`) and keeps as one piece: 50 robots' frames (~4 KB) give 128
/// ticks, 500 robots' (~42 KB) 12.
pub const CHUNK_BYTES: usize = 512 * 1024;
/// A chunk's length in ticks stays within these bounds, whatever the frames' size.
pub const CHUNK_TICKS: std::ops::RangeInclusive<usize> = 10..=500;

/// Most frames one [`Feed::since`] hands a stream (it asks again for the rest).
const SINCE_MAX: usize = 64;

/// Where the frames' JSON lives: an unlinked file, and each frame's (offset, length) in it.
struct Spill {
    file: File,
    index: Vec<(u64, u32)>,
    end: u64,
}

impl Spill {
    fn new() -> std::io::Result<Spill> {
        static N: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("swarm-view-{}-{n}.json", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&path)?;
        // Unlinked at once: the open file lives until the feed is dropped, then it is gone.
        std::fs::remove_file(&path)?;
        Ok(Spill {
            file,
            index: Vec::new(),
            end: 0,
        })
    }

    fn push(&mut self, f: &str) -> std::io::Result<()> {
        self.file.write_all_at(f.as_bytes(), self.end)?;
        self.index.push((self.end, f.len() as u32));
        self.end += f.len() as u64;
        Ok(())
    }

    fn get(&self, i: usize) -> String {
        let (at, len) = self.index[i];
        let mut b = vec![0u8; len as usize];
        match self.file.read_exact_at(&mut b, at) {
            // Written from a String by push: UTF-8.
            Ok(()) => String::from_utf8(b).unwrap_or_default(),
            Err(_) => String::new(),
        }
    }

    fn range(&self, from: usize, to: usize) -> Vec<String> {
        let to = to.min(self.index.len());
        (from.min(to)..to).map(|i| self.get(i)).collect()
    }
}

#[derive(Default)]
struct State {
    meta: Option<String>,
    /// None until the first frame (or when the temp dir cannot take the spill file: `error`).
    frames: Option<Spill>,
    /// No more frames will come (the recording is complete, or the run ended).
    ended: bool,
    /// Ticks per chunk given by the user (`view --chunk`), instead of [`CHUNK_BYTES`]'.
    chunk: Option<usize>,
    error: Option<String>,
    /// What the run has shown so far, as JSON (`frame::Seen`).
    seen: Option<String>,
}

/// Frames so far of one run.
#[derive(Clone, Default)]
pub struct Feed {
    inner: Arc<(Mutex<State>, Condvar)>,
}

impl Feed {
    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.inner.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The meta JSON, once the header is read.
    pub fn meta(&self) -> Option<String> {
        self.lock().meta.clone()
    }

    pub fn error(&self) -> Option<String> {
        self.lock().error.clone()
    }

    /// Up to [`SINCE_MAX`] frames from index `from` on, and whether the feed has ended.
    pub fn since(&self, from: usize) -> (Vec<String>, bool) {
        let s = self.lock();
        let frames = s.frames.as_ref().map_or(Vec::new(), |sp| {
            sp.range(from, from.saturating_add(SINCE_MAX))
        });
        // Ended only counts once every frame has been handed out.
        let ended = s.ended && from + frames.len() >= s.count();
        (frames, ended)
    }

    /// Frames `from..to` (clipped to those there are).
    pub fn range(&self, from: usize, to: usize) -> Vec<String> {
        let s = self.lock();
        s.frames
            .as_ref()
            .map_or(Vec::new(), |sp| sp.range(from, to))
    }

    /// Chunks of `ticks` ticks from now on (`view --chunk`; 0: from [`CHUNK_BYTES`]).
    pub fn set_chunk(&self, ticks: usize) {
        self.lock().chunk = (ticks > 0).then_some(ticks);
    }

    /// No more frames will come.
    pub fn ended(&self) -> bool {
        self.lock().ended
    }

    pub fn len(&self) -> usize {
        self.lock().count()
    }

    /// Ticks per chunk: [`CHUNK_BYTES`] over the first frame's size (the bounds' smallest
    /// while there is none).
    pub fn chunk(&self) -> usize {
        let s = self.lock();
        if let Some(c) = s.chunk {
            return c.max(1);
        }
        let first = s.frames.as_ref().and_then(|sp| sp.index.first());
        let per = first.map_or(usize::MAX, |&(_, len)| (len as usize).max(1));
        (CHUNK_BYTES / per).clamp(*CHUNK_TICKS.start(), *CHUNK_TICKS.end())
    }

    /// Waits up to `timeout` for a frame past `seen` or the end.
    pub fn wait(&self, seen: usize, timeout: Duration) {
        let s = self.lock();
        let _ = self
            .inner
            .1
            .wait_timeout_while(s, timeout, |s| s.count() <= seen && !s.ended);
    }

    /// What the run has shown so far (`frame::Seen` as JSON; None before the first frame).
    pub fn seen(&self) -> Option<String> {
        self.lock().seen.clone()
    }

    /// Frames tick `t` and pushes it; what the run has shown so far follows.
    fn push_tick(&self, framer: &mut Framer, t: &swarm::recording::TickRecord) {
        let f = framer.json(t);
        let seen = serde_json::to_string(framer.seen()).expect("seen JSON");
        self.lock().seen = Some(seen);
        self.push(f);
    }

    fn set_meta(&self, m: String) {
        self.lock().meta = Some(m);
        self.inner.1.notify_all();
    }

    fn push(&self, f: String) {
        let mut s = self.lock();
        if s.error.is_some() {
            return;
        }
        if s.frames.is_none() {
            match Spill::new() {
                Ok(sp) => s.frames = Some(sp),
                Err(e) => s.set_error(format!("the viewer's spill file: {e}")),
            }
        }
        if let Some(Err(e)) = s.frames.as_mut().map(|sp| sp.push(&f)) {
            s.set_error(format!("the viewer's spill file: {e}"));
        }
        drop(s);
        self.inner.1.notify_all();
    }

    /// No more frames (also: the live run is over).
    pub fn end(&self) {
        self.lock().ended = true;
        self.inner.1.notify_all();
    }

    fn fail(&self, e: String) {
        self.lock().set_error(e);
        self.inner.1.notify_all();
    }
}

impl State {
    fn count(&self) -> usize {
        self.frames.as_ref().map_or(0, |sp| sp.index.len())
    }

    fn set_error(&mut self, e: String) {
        self.error = Some(e);
        self.ended = true;
    }
}

/// Errors of reading a finished recording.
#[derive(Debug, thiserror::Error)]
pub enum FeedError {
    #[error("{path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Meta { path: PathBuf, source: MetaError },
}

/// The whole of a finished run's recording.
pub fn finished(path: &Path, run: &str) -> Result<Feed, FeedError> {
    let read = |source| FeedError::Read {
        path: path.to_path_buf(),
        source,
    };
    let f = std::fs::File::open(path).map_err(read)?;
    let mut inp = std::io::BufReader::new(f);
    let header = read_finished_header(&mut inp).map_err(read)?;
    let meta = Meta::of(&header, run, false).map_err(|source| FeedError::Meta {
        path: path.to_path_buf(),
        source,
    })?;
    let feed = Feed::default();
    feed.set_meta(serde_json::to_string(&meta).expect("meta JSON"));
    // One tick at a time: neither the records nor their JSON are held.
    let mut framer = meta.framer();
    let mut reader = TickReader::new(&header);
    while let Some(t) = reader.next(&mut inp).map_err(read)? {
        feed.push_tick(&mut framer, &t);
    }
    feed.end();
    match feed.error() {
        Some(e) => Err(read(std::io::Error::other(e))),
        None => Ok(feed),
    }
}

/// Follows a live run's recording at `path` (it may not exist yet) on a thread of its own,
/// until `feed.end()` is called and every byte written by then is read.
pub fn follow(path: PathBuf, run: String) -> Feed {
    let feed = Feed::default();
    let f = feed.clone();
    std::thread::spawn(move || {
        if let Err(e) = follow_loop(&path, &run, &f) {
            f.fail(format!("{}: {e}", path.display()));
        }
    });
    feed
}

fn follow_loop(path: &Path, run: &str, feed: &Feed) -> Result<(), String> {
    let mut file = loop {
        if let Ok(f) = std::fs::File::open(path) {
            break f;
        }
        if feed.lock().ended {
            return Ok(());
        }
        std::thread::sleep(FOLLOW_POLL);
    };
    let mut buf: Vec<u8> = Vec::new();
    let mut pos = 0usize;
    let mut header: Option<(RecordingHeader, TickReader, Framer)> = None;
    loop {
        // Read what the feed's end leaves: after end(), one more pass reads the last bytes.
        let last_pass = feed.lock().ended;
        let mut chunk = [0u8; 64 * 1024];
        loop {
            let n = file.read(&mut chunk).map_err(|e| e.to_string())?;
            if n == 0 {
                break;
            }
            buf.extend_from_slice(&chunk[..n]);
        }
        loop {
            let mut cur = &buf[pos..];
            let before = cur.len();
            match header.as_mut() {
                None => match read_header(&mut cur) {
                    Ok(h) => {
                        let meta = Meta::of(&h, run, true).map_err(|e| e.to_string())?;
                        feed.set_meta(serde_json::to_string(&meta).expect("meta JSON"));
                        let r = TickReader::new(&h);
                        header = Some((h, r, meta.framer()));
                    }
                    // The header is not all written yet.
                    Err(_) => break,
                },
                Some((_, reader, framer)) => match reader.next(&mut cur) {
                    Ok(Some(t)) => feed.push_tick(framer, &t),
                    // A tick not all written yet.
                    Ok(None) => break,
                    Err(e) => return Err(e.to_string()),
                },
            }
            pos += before - cur.len();
        }
        if pos > 1 << 20 {
            buf.drain(..pos);
            pos = 0;
        }
        if last_pass {
            return Ok(());
        }
        std::thread::sleep(FOLLOW_POLL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use swarm::recording::{RecordingWriter, TickRecord, RECORDING_VERSION_LAYER};

    #[test]
    fn frames_live_in_an_unlinked_spill_file_and_a_stream_gets_them_in_pieces() {
        let feed = Feed::default();
        let frames: Vec<String> = (0..100).map(|k| format!("{{\"tick\":{k}}}")).collect();
        for f in &frames {
            feed.push(f.clone());
        }
        // Nothing of the spill file is left in the temp dir while it is in use.
        let me = format!("swarm-view-{}-", std::process::id());
        let left = std::fs::read_dir(std::env::temp_dir())
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with(&me))
            .count();
        assert_eq!(left, 0);
        assert_eq!(feed.len(), 100);
        assert_eq!(feed.range(40, 43), frames[40..43].to_vec());
        assert_eq!(feed.range(98, 500), frames[98..].to_vec());
        assert!(feed.range(120, 130).is_empty());
        feed.end();
        // A stream from 0 gets SINCE_MAX frames, then the rest with the end.
        let (a, ended) = feed.since(0);
        assert_eq!((a.len(), ended), (SINCE_MAX, false));
        let (b, ended) = feed.since(SINCE_MAX);
        assert_eq!((b.len(), ended), (100 - SINCE_MAX, true));
        assert_eq!([a, b].concat(), frames);
        assert_eq!(feed.since(100), (vec![], true));
    }

    #[test]
    fn a_growing_recording_is_followed_across_pieces_cut_inside_the_header_and_records() {
        let sc = Scenario::default();
        let header = RecordingHeader {
            version: RECORDING_VERSION_LAYER,
            robots: 2,
            seed: 1,
            scenario: sc.to_toml(),
        };
        let mut bytes = Vec::new();
        let mut w = RecordingWriter::new(&mut bytes, &header).unwrap();
        for k in 0..30u64 {
            w.push(&TickRecord {
                tick: k,
                poses: vec![[k as f64, 1.0, 0.0], [2.0, k as f64, 0.0]],
                alive: vec![1, 1],
                states: vec![0, 1],
                events: vec![],
                radio: Default::default(),
                radio_bytes: Default::default(),
                extra: None,
                layer: Some(vec![swarm::layer::Mark::Disc {
                    at: [k as f64 / 10.0, 0.0],
                    px: 3,
                    fill: [1, 2, 3],
                    outline: None,
                }]),
                deliveries: None,
            })
            .unwrap();
        }
        w.finish().unwrap();
        let path = std::env::temp_dir().join(format!("feed-{}.bin", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let feed = follow(path.clone(), "t".into());
        let mut f = std::fs::File::create(&path).unwrap();
        // Pieces that end inside the header, then inside records.
        let hl = bincode::serde::encode_to_vec(&header, bincode::config::standard())
            .unwrap()
            .len();
        let body = bytes.len() - hl;
        let cuts = [7, hl + body / 3, hl + body / 2 + 5, bytes.len()];
        let mut from = 0;
        let mut seen = vec![];
        for &c in &cuts {
            f.write_all(&bytes[from..c]).unwrap();
            f.flush().unwrap();
            from = c;
            std::thread::sleep(FOLLOW_POLL * 4);
            seen.push(feed.len());
        }
        feed.end();
        let t = std::time::Instant::now();
        while feed.len() < 30 && t.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(FOLLOW_POLL);
        }
        let _ = std::fs::remove_file(&path);
        assert_eq!(seen[0], 0, "no tick before the header is whole");
        assert!(seen[1] > 0 && seen[1] < seen[2] && seen[2] < 30, "{seen:?}");
        let (frames, ended) = feed.since(0);
        assert!(ended);
        assert_eq!(frames.len(), 30);
        let last: serde_json::Value = serde_json::from_str(&frames[29]).unwrap();
        assert_eq!(last["tick"], 29);
        assert_eq!(last["poses"][1][1], 29.0);
        assert_eq!(last["layer"][0]["Disc"]["at"][0], 2.9);
        assert!(feed.meta().unwrap().contains("\"live\":true"));
    }
}
