//! The viewer's HTTP server on 127.0.0.1: the embedded page, the run's frames, the live stream
//! (server-sent events) and the kill button's POST. Every request is read within limits
//! (`http.rs`) and checked (`guard.rs`: Host, Origin, Sec-Fetch-Site; the kill's token)
//! before it is routed: refused with 414 / 431 / 400 / 403.
//!
//! Routes:
//! - `GET /` (any query: `?tick=N` shows tick N, `?robot=I` selects robot I, `?trail=K`): the
//!   page, whose `/run.js` asks for the frames that tick and its trail need;
//! - `GET /viewer.js`, `GET /viewer.css`: the page's code and style (embedded, no CDN);
//! - `GET /run.js?tick=N&trail=K`: `window.RUN = {meta, ended, count, chunk, first, seen,
//!   frames}`: the frame count so far, the chunk length (ticks the page asks for at a time),
//!   what the run has shown so far (its legend's states and marks) and the frames of the
//!   chunks from tick N - K to tick N (N: the newest of a live run, else 0).
//!   Loaded before the page's script, so a page drawn at load shows them: a headless
//!   screenshot needs no JS driver;
//! - `GET /api/meta`, `GET /api/frames?from=K&to=L` (L: the end if left out): JSON;
//! - `GET /api/stream?from=K`: server-sent events, one `frame` event per tick from index K
//!   on, then an `end` event;
//! - `POST /api/kill?robot=I`: SIGKILL robot I's agent (live runs of the processes executor),
//!   as `orchestrator kill` does; only with the page's Origin and its token (`X-Swarm-Token`).

use super::feed::Feed;
use super::guard::Guard;
use super::http::{self, Request};
use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

const INDEX_HTML: &str = include_str!("page/index.html");
const VIEWER_JS: &str = include_str!("page/viewer.js");
const VIEWER_CSS: &str = include_str!("page/viewer.css");

/// The page's trail length when its URL gives none (page/index.html's `#trail` input).
const DEFAULT_TRAIL: usize = 40;

/// How long a stream request waits for a frame before it writes a keep-alive comment (which
/// also finds out that a page has gone).
const STREAM_IDLE: Duration = Duration::from_secs(2);

/// Most connections served at once (each has a thread; a page holds one for its stream and
/// opens one per chunk it asks for); more are answered 503.
const MAX_CONNECTIONS: usize = 64;

/// What the kill button does: robot -> message (Ok: killed; Err: why not).
pub type KillFn = dyn Fn(u32) -> Result<String, String> + Send + Sync;

/// Why the server did not start.
#[derive(Debug, thiserror::Error)]
#[error("cannot serve on 127.0.0.1:{port}: {message}")]
pub struct ServeError {
    pub port: u16,
    pub message: String,
}

/// A running viewer server.
pub struct Viewer {
    pub url: String,
    addr: std::net::SocketAddr,
    stopped: Arc<AtomicBool>,
}

/// What every request's thread shares.
struct Shared {
    feed: Feed,
    kill: Option<Arc<KillFn>>,
    guard: Guard,
    open: AtomicUsize,
}

impl Viewer {
    /// Serves `feed` on 127.0.0.1:`port` (0: any free port) from a thread of its own; each
    /// connection is answered on a thread of its own.
    pub fn start(
        port: u16,
        feed: Feed,
        kill: Option<std::sync::Arc<KillFn>>,
    ) -> Result<Viewer, ServeError> {
        let err = |e: std::io::Error| ServeError {
            port,
            message: e.to_string(),
        };
        let listener = TcpListener::bind(("127.0.0.1", port)).map_err(err)?;
        let addr = listener.local_addr().map_err(err)?;
        let shared = Arc::new(Shared {
            feed,
            kill,
            guard: Guard::new(addr.port()),
            open: AtomicUsize::new(0),
        });
        let stopped = Arc::new(AtomicBool::new(false));
        let stop = stopped.clone();
        std::thread::spawn(move || {
            for conn in listener.incoming() {
                if stop.load(Ordering::SeqCst) {
                    return;
                }
                let Ok(mut s) = conn else { continue };
                if shared.open.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
                    shared.open.fetch_sub(1, Ordering::SeqCst);
                    http::respond(&mut s, 503, "text/plain", b"too many connections\n");
                    continue;
                }
                let shared = shared.clone();
                std::thread::spawn(move || {
                    serve(s, &shared);
                    shared.open.fetch_sub(1, Ordering::SeqCst);
                });
            }
        });
        Ok(Viewer {
            url: format!("http://{addr}/"),
            addr,
            stopped,
        })
    }

    /// Stops accepting requests (streams under way end with their feed).
    pub fn stop(&self) {
        self.stopped.store(true, Ordering::SeqCst);
        // Wakes the accept loop, which then sees the flag.
        let _ = TcpStream::connect(self.addr);
    }
}

/// The value of `key` in the query of `url`.
fn query(url: &str, key: &str) -> Option<String> {
    let q = url.split_once('?')?.1;
    q.split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v.to_string())
}

/// A whole number `key` of the query of `url`.
fn number(url: &str, key: &str) -> Option<usize> {
    query(url, key).and_then(|v| v.parse::<usize>().ok())
}

/// The page, its `/run.js` asking for what the page's own `?tick=` and `?trail=` need (numbers
/// only go into the HTML), and the server's kill token (hex digits) in its `<meta>`.
fn index_html(url: &str, token: &str) -> String {
    let mut q = Vec::new();
    for key in ["tick", "trail"] {
        if let Some(v) = number(url, key) {
            q.push(format!("{key}={v}"));
        }
    }
    let src = if q.is_empty() {
        "/run.js".to_string()
    } else {
        format!("/run.js?{}", q.join("&amp;"))
    };
    INDEX_HTML
        .replace("src=\"/run.js\"", &format!("src=\"{src}\""))
        .replace("content=\"KILL-TOKEN\"", &format!("content=\"{token}\""))
}

/// The first and the end of the frames the page needs at load for tick `tick` (None: the
/// newest of a live run, else 0) with a trail of `trail` ticks: whole chunks of `chunk`
/// ticks of the `count` there are.
pub fn load_window(
    tick: Option<usize>,
    trail: usize,
    live: bool,
    count: usize,
    chunk: usize,
) -> (usize, usize) {
    if count == 0 {
        return (0, 0);
    }
    let t = match tick {
        Some(t) => t.min(count - 1),
        None if live => count - 1,
        None => 0,
    };
    let first = t.saturating_sub(trail) / chunk * chunk;
    let end = ((t / chunk + 1) * chunk).min(count);
    (first, end)
}

fn run_js(url: &str, feed: &Feed) -> String {
    match (feed.meta(), feed.error()) {
        (Some(m), _) => {
            let live = m.contains("\"live\":true");
            let (ended, count) = (feed.ended(), feed.len());
            let chunk = feed.chunk();
            let trail = number(url, "trail").unwrap_or(DEFAULT_TRAIL);
            let (first, end) = load_window(number(url, "tick"), trail, live, count, chunk);
            let frames = feed.range(first, end);
            let seen = feed.seen().unwrap_or_else(|| "null".into());
            format!(
                "window.RUN = {{\"meta\": {m}, \"ended\": {ended}, \"count\": {count}, \"chunk\": {chunk}, \"first\": {first}, \"seen\": {seen}, \"frames\": [{}]}};\n",
                frames.join(",\n")
            )
        }
        (None, Some(e)) => format!("window.RUN_ERROR = {};\n", json_str(&e)),
        (None, None) => "window.RUN = null;\n".to_string(),
    }
}

/// A response's status, content type and body.
type Reply = (u16, &'static str, Vec<u8>);

fn reply(status: u16, kind: &'static str, body: impl Into<Vec<u8>>) -> Reply {
    (status, kind, body.into())
}

/// One connection: its request read (within the limits), checked (Host, Origin,
/// Sec-Fetch-Site; the kill's token) and answered.
fn serve(mut s: TcpStream, shared: &Shared) {
    let req = match http::read_request(&mut s) {
        Ok(r) => r,
        Err(e) => {
            if let Some(status) = e.status() {
                http::refuse_unread(&mut s, status, &e.to_string());
            }
            return;
        }
    };
    if let Err(e) = shared.guard.check(&req) {
        http::respond(&mut s, 403, "text/plain", format!("{e}\n").as_bytes());
        return;
    }
    if req.method == "GET" && req.path() == "/api/stream" {
        stream(s, &shared.feed, number(&req.target, "from").unwrap_or(0));
        return;
    }
    let (status, kind, body) = route(&req, shared);
    http::respond(&mut s, status, kind, &body);
}

fn route(req: &Request, shared: &Shared) -> Reply {
    let (url, feed) = (req.target.as_str(), &shared.feed);
    let from = number(url, "from").unwrap_or(0);
    match (req.method.as_str(), req.path()) {
        ("GET", "/") | ("GET", "/index.html") => reply(
            200,
            "text/html; charset=utf-8",
            index_html(url, shared.guard.token()),
        ),
        ("GET", "/viewer.js") => reply(200, "text/javascript", VIEWER_JS),
        ("GET", "/viewer.css") => reply(200, "text/css", VIEWER_CSS),
        ("GET", "/run.js") => reply(200, "text/javascript", run_js(url, feed)),
        ("GET", "/api/meta") => match feed.meta() {
            Some(m) => reply(200, "application/json", m),
            None => reply(503, "application/json", "{\"error\": \"no header yet\"}"),
        },
        ("GET", "/api/frames") => {
            let to = number(url, "to").unwrap_or(usize::MAX);
            let frames = feed.range(from, to);
            reply(200, "application/json", format!("[{}]", frames.join(",\n")))
        }
        ("POST", "/api/kill") => {
            if let Err(e) = shared.guard.check_kill(req) {
                return reply(403, "text/plain", format!("{e}\n"));
            }
            let robot = query(url, "robot").and_then(|v| v.parse::<u32>().ok());
            match (shared.kill.as_deref(), robot) {
                (_, None) => reply(400, "text/plain", "give ?robot=I\n"),
                (None, _) => reply(
                    409,
                    "text/plain",
                    "not a live run of the processes executor: no agent to kill\n",
                ),
                (Some(k), Some(r)) => match k(r) {
                    Ok(m) => reply(200, "text/plain", m + "\n"),
                    Err(m) => reply(409, "text/plain", m + "\n"),
                },
            }
        }
        (_, "/" | "/index.html" | "/viewer.js" | "/viewer.css" | "/run.js" | "/api/meta")
        | (_, "/api/frames" | "/api/stream" | "/api/kill") => {
            reply(405, "text/plain", "method not allowed\n")
        }
        _ => reply(404, "text/plain", "not found\n"),
    }
}

fn json_str(s: &str) -> String {
    serde_json::to_string(s).expect("string JSON")
}

/// Server-sent events: every frame from index `from` on as it comes, then `end`. Ends at the
/// first failed write (the page has gone): the feed is not held up by it.
fn stream(mut w: TcpStream, feed: &Feed, from: usize) {
    let head = http::head(200, "text/event-stream", None);
    if w.write_all(head.as_bytes())
        .and_then(|_| w.flush())
        .is_err()
    {
        return;
    }
    let mut next = from;
    loop {
        let (frames, ended) = feed.since(next);
        let mut out = String::new();
        for f in &frames {
            out.push_str("event: frame\ndata: ");
            out.push_str(f);
            out.push_str("\n\n");
        }
        next += frames.len();
        if frames.is_empty() && !ended {
            out.push_str(": idle\n\n");
        }
        if ended && frames.is_empty() {
            out.push_str("event: end\ndata: {}\n\n");
        }
        if w.write_all(out.as_bytes()).and_then(|_| w.flush()).is_err() {
            return;
        }
        if ended && frames.is_empty() {
            return;
        }
        if frames.is_empty() {
            feed.wait(next, STREAM_IDLE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_load_window_is_whole_chunks_from_the_trails_start_to_the_ticks_chunks_end() {
        // Chunks of 10 of 95 frames: tick 42 with a trail of 5 needs 37..=42: chunks 30..50.
        assert_eq!(load_window(Some(42), 5, false, 95, 10), (30, 50));
        // A trail back into tick 0; a tick past the end shows the last.
        assert_eq!(load_window(Some(3), 40, false, 95, 10), (0, 10));
        assert_eq!(load_window(Some(500), 0, false, 95, 10), (90, 95));
        // No tick: a replay starts at 0, a live page at the newest.
        assert_eq!(load_window(None, 0, false, 95, 10), (0, 10));
        assert_eq!(load_window(None, 12, true, 95, 10), (80, 95));
        assert_eq!(load_window(None, 0, true, 0, 10), (0, 0));
    }

    #[test]
    fn the_page_asks_run_js_for_its_tick_and_trail_and_nothing_else_reaches_the_html() {
        let page = index_html("/?tick=40&trail=0&robot=3", "ab12");
        assert!(
            page.contains("src=\"/run.js?tick=40&amp;trail=0\""),
            "{page}"
        );
        assert!(
            page.contains("<meta name=\"swarm-kill-token\" content=\"ab12\">"),
            "{page}"
        );
        let page = index_html("/?tick=%22%3E%3Cscript%3E&trail=x", "ab12");
        assert!(page.contains("src=\"/run.js\""), "{page}");
    }
}
