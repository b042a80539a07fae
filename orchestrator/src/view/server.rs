//! The viewer's HTTP server on 127.0.0.1: the embedded page, the run's frames, the live stream
//! (server-sent events) and the kill button's POST.
//!
//! Routes:
//! - `GET /` (any query: `?tick=N` shows tick N, `?robot=I` selects robot I, `?trail=K`): the
//!   page, whose `/run.js` asks for the frames that tick and its trail need;
//! - `GET /viewer.js`, `GET /viewer.css`: the page's code and style (embedded, no CDN);
//! - `GET /run.js?tick=N&trail=K`: `window.RUN = {meta, ended, count, chunk, first, frames}`:
//!   the frame count so far, the chunk length (ticks the page asks for at a time) and the
//!   frames of the chunks from tick N - K to tick N (N: the newest of a live run, else 0).
//!   Loaded before the page's script, so a page drawn at load shows them: a headless
//!   screenshot needs no JS driver;
//! - `GET /api/meta`, `GET /api/frames?from=K&to=L` (L: the end if left out): JSON;
//! - `GET /api/stream?from=K`: server-sent events, one `frame` event per tick from index K
//!   on, then an `end` event;
//! - `POST /api/kill?robot=I`: SIGKILL robot I's agent (live runs of the processes executor),
//!   as `orchestrator kill` does.

use super::feed::Feed;
use std::io::Write;
use std::time::Duration;
use tiny_http::{Header, Method, Request, Response, Server};

const INDEX_HTML: &str = include_str!("page/index.html");
const VIEWER_JS: &str = include_str!("page/viewer.js");
const VIEWER_CSS: &str = include_str!("page/viewer.css");

/// The page's trail length when its URL gives none (page/index.html's `#trail` input).
const DEFAULT_TRAIL: usize = 40;

/// How long a stream request waits for a frame before it writes a keep-alive comment (which
/// also finds out that a page has gone).
const STREAM_IDLE: Duration = Duration::from_secs(2);

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
    server: std::sync::Arc<Server>,
}

impl Viewer {
    /// Serves `feed` on 127.0.0.1:`port` (0: any free port) from a thread of its own; each
    /// request is answered on a thread of its own.
    pub fn start(
        port: u16,
        feed: Feed,
        kill: Option<std::sync::Arc<KillFn>>,
    ) -> Result<Viewer, ServeError> {
        let server = Server::http(("127.0.0.1", port)).map_err(|e| ServeError {
            port,
            message: e.to_string(),
        })?;
        let addr = server.server_addr().to_ip().ok_or_else(|| ServeError {
            port,
            message: "not an IP address".into(),
        })?;
        let server = std::sync::Arc::new(server);
        let s = server.clone();
        std::thread::spawn(move || {
            for req in s.incoming_requests() {
                let feed = feed.clone();
                let kill = kill.clone();
                std::thread::spawn(move || handle(req, &feed, kill.as_deref()));
            }
        });
        Ok(Viewer {
            url: format!("http://{addr}/"),
            server,
        })
    }

    /// Stops accepting requests (streams under way end with their feed).
    pub fn stop(&self) {
        self.server.unblock();
    }
}

fn header(k: &str, v: &str) -> Header {
    Header::from_bytes(k.as_bytes(), v.as_bytes()).expect("valid header")
}

fn text(status: u16, body: String, kind: &str) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string(body)
        .with_status_code(status)
        .with_header(header("Content-Type", kind))
        .with_header(header("Cache-Control", "no-store"))
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
/// only go into the HTML).
fn index_html(url: &str) -> String {
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
    INDEX_HTML.replace("src=\"/run.js\"", &format!("src=\"{src}\""))
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
            format!(
                "window.RUN = {{\"meta\": {m}, \"ended\": {ended}, \"count\": {count}, \"chunk\": {chunk}, \"first\": {first}, \"frames\": [{}]}};\n",
                frames.join(",\n")
            )
        }
        (None, Some(e)) => format!("window.RUN_ERROR = {};\n", json_str(&e)),
        (None, None) => "window.RUN = null;\n".to_string(),
    }
}

fn handle(req: Request, feed: &Feed, kill: Option<&KillFn>) {
    let url = req.url().to_string();
    let path = url.split('?').next().unwrap_or("/").to_string();
    let from = number(&url, "from").unwrap_or(0);
    let resp = match (req.method(), path.as_str()) {
        (Method::Get, "/") | (Method::Get, "/index.html") => {
            text(200, index_html(&url), "text/html; charset=utf-8")
        }
        (Method::Get, "/viewer.js") => text(200, VIEWER_JS.into(), "text/javascript"),
        (Method::Get, "/viewer.css") => text(200, VIEWER_CSS.into(), "text/css"),
        (Method::Get, "/run.js") => text(200, run_js(&url, feed), "text/javascript"),
        (Method::Get, "/api/meta") => match feed.meta() {
            Some(m) => text(200, m, "application/json"),
            None => text(
                503,
                "{\"error\": \"no header yet\"}".into(),
                "application/json",
            ),
        },
        (Method::Get, "/api/frames") => {
            let to = number(&url, "to").unwrap_or(usize::MAX);
            let frames = feed.range(from, to);
            text(200, format!("[{}]", frames.join(",\n")), "application/json")
        }
        (Method::Get, "/api/stream") => {
            stream(req, feed, from);
            return;
        }
        (Method::Post, "/api/kill") => {
            let robot = query(&url, "robot").and_then(|v| v.parse::<u32>().ok());
            match (kill, robot) {
                (_, None) => text(400, "give ?robot=I\n".into(), "text/plain"),
                (None, _) => text(
                    409,
                    "not a live run of the processes executor: no agent to kill\n".into(),
                    "text/plain",
                ),
                (Some(k), Some(r)) => match k(r) {
                    Ok(m) => text(200, m + "\n", "text/plain"),
                    Err(m) => text(409, m + "\n", "text/plain"),
                },
            }
        }
        _ => text(404, "not found\n".into(), "text/plain"),
    };
    // A page that went away: nothing to do.
    let _ = req.respond(resp);
}

fn json_str(s: &str) -> String {
    serde_json::to_string(s).expect("string JSON")
}

/// Server-sent events: every frame from index `from` on as it comes, then `end`. Ends at the
/// first failed write (the page has gone): the feed is not held up by it.
fn stream(req: Request, feed: &Feed, from: usize) {
    let mut w = req.into_writer();
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n";
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
        let page = index_html("/?tick=40&trail=0&robot=3");
        assert!(
            page.contains("src=\"/run.js?tick=40&amp;trail=0\""),
            "{page}"
        );
        let page = index_html("/?tick=%22%3E%3Cscript%3E&trail=x");
        assert!(page.contains("src=\"/run.js\""), "{page}");
    }
}
