//! The frames of a run, shared by the page's requests: all of a finished recording at once, or
//! a live run's recording.bin followed as the world writes it.
//!
//! The follower reads the file on its own thread and never talks to the world: the world only
//! flushes each tick (`world --live`), so a page that is slow, or gone, cannot slow the run.
//! Every stream request reads the shared list from its own position; none waits for another.

use super::frame::Framer;
use super::meta::{Meta, MetaError};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;
use swarm::recording::{read_header, RecordingHeader, TickReader};
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

#[derive(Default)]
struct State {
    meta: Option<String>,
    frames: Vec<String>,
    /// No more frames will come (the recording is complete, or the run ended).
    ended: bool,
    /// Ticks per chunk given by the user (`view --chunk`), instead of [`CHUNK_BYTES`]'.
    chunk: Option<usize>,
    error: Option<String>,
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

    /// Frames from index `from` on (a copy), and whether the feed has ended.
    pub fn since(&self, from: usize) -> (Vec<String>, bool) {
        let s = self.lock();
        (s.frames.get(from..).unwrap_or(&[]).to_vec(), s.ended)
    }

    /// Frames `from..to` (clipped to those there are; a copy).
    pub fn range(&self, from: usize, to: usize) -> Vec<String> {
        let s = self.lock();
        let to = to.min(s.frames.len());
        s.frames.get(from.min(to)..to).unwrap_or(&[]).to_vec()
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
        self.lock().frames.len()
    }

    /// Ticks per chunk: [`CHUNK_BYTES`] over the first frame's size (the bounds' smallest
    /// while there is none).
    pub fn chunk(&self) -> usize {
        let s = self.lock();
        if let Some(c) = s.chunk {
            return c.max(1);
        }
        let per = s.frames.first().map_or(usize::MAX, |f| f.len().max(1));
        (CHUNK_BYTES / per).clamp(*CHUNK_TICKS.start(), *CHUNK_TICKS.end())
    }

    /// Waits up to `timeout` for a frame past `seen` or the end.
    pub fn wait(&self, seen: usize, timeout: Duration) {
        let s = self.lock();
        let _ = self
            .inner
            .1
            .wait_timeout_while(s, timeout, |s| s.frames.len() <= seen && !s.ended);
    }

    fn set_meta(&self, m: String) {
        self.lock().meta = Some(m);
        self.inner.1.notify_all();
    }

    fn push(&self, f: String) {
        self.lock().frames.push(f);
        self.inner.1.notify_all();
    }

    /// No more frames (also: the live run is over).
    pub fn end(&self) {
        self.lock().ended = true;
        self.inner.1.notify_all();
    }

    fn fail(&self, e: String) {
        let mut s = self.lock();
        s.error = Some(e);
        s.ended = true;
        self.inner.1.notify_all();
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
    let (header, ticks) = swarm::recording::read_recording(f).map_err(read)?;
    let meta = Meta::of(&header, run, false).map_err(|source| FeedError::Meta {
        path: path.to_path_buf(),
        source,
    })?;
    let feed = Feed::default();
    feed.set_meta(serde_json::to_string(&meta).expect("meta JSON"));
    let mut framer = Framer::default();
    for t in &ticks {
        feed.push(framer.json(t));
    }
    feed.end();
    Ok(feed)
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
    let mut header: Option<(RecordingHeader, TickReader)> = None;
    let mut framer = Framer::default();
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
                        header = Some((h, r));
                    }
                    // The header is not all written yet.
                    Err(_) => break,
                },
                Some((_, reader)) => match reader.next(&mut cur) {
                    Ok(Some(t)) => feed.push(framer.json(&t)),
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
