//! The viewer's HTTP server on 127.0.0.1: the embedded page, the run's frames, the live stream
//! (server-sent events) and the kill button's POST.
//!
//! Routes:
//! - `GET /` (any query: `?tick=N` shows tick N, `?robot=I` selects robot I): the page;
//! - `GET /viewer.js`, `GET /viewer.css`: the page's code and style (embedded, no CDN);
//! - `GET /run.js`: `window.RUN = {meta, frames}`, the frames so far (loaded before the page's
//!   script, so a page drawn at load shows them: a headless screenshot needs no JS driver);
//! - `GET /api/meta`, `GET /api/frames?from=K`: the same as JSON;
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

fn handle(req: Request, feed: &Feed, kill: Option<&KillFn>) {
    let url = req.url().to_string();
    let path = url.split('?').next().unwrap_or("/").to_string();
    let from = query(&url, "from")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(0);
    let resp = match (req.method(), path.as_str()) {
        (Method::Get, "/") | (Method::Get, "/index.html") => {
            text(200, INDEX_HTML.into(), "text/html; charset=utf-8")
        }
        (Method::Get, "/viewer.js") => text(200, VIEWER_JS.into(), "text/javascript"),
        (Method::Get, "/viewer.css") => text(200, VIEWER_CSS.into(), "text/css"),
        (Method::Get, "/run.js") => {
            let body = match (feed.meta(), feed.error()) {
                (Some(m), _) => {
                    let (frames, ended) = feed.since(0);
                    format!(
                        "window.RUN = {{\"meta\": {m}, \"ended\": {ended}, \"frames\": [{}]}};\n",
                        frames.join(",\n")
                    )
                }
                (None, Some(e)) => format!("window.RUN_ERROR = {};\n", json_str(&e)),
                (None, None) => "window.RUN = null;\n".to_string(),
            };
            text(200, body, "text/javascript")
        }
        (Method::Get, "/api/meta") => match feed.meta() {
            Some(m) => text(200, m, "application/json"),
            None => text(
                503,
                "{\"error\": \"no header yet\"}".into(),
                "application/json",
            ),
        },
        (Method::Get, "/api/frames") => {
            let (frames, _) = feed.since(from);
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
