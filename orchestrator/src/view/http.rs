//! The viewer's HTTP/1.1 connections: a request's head read with limits and parsed with
//! `httparse`, one request per connection (`Connection: close`), a response written whole.
//!
//! The limits are what a page of this viewer needs many times over: a request line of a few
//! hundred bytes, a head of a few KB (cookies of other local servers included), a dozen
//! headers. A head over them is answered 414 / 431 and the connection closed, so a request
//! of a 10 MB URL or 20,000 headers is never held in memory.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpStream};
use std::time::{Duration, Instant};

/// Longest request line (method, target, version): the page's longest is under 200 bytes.
pub const MAX_REQUEST_LINE: usize = 4096;
/// Longest request head (request line and headers): Chromium sends about 1 KB, more with the
/// cookies other servers on localhost set (cookies are per host, not per port).
pub const MAX_HEAD_BYTES: usize = 32 * 1024;
/// Most headers in a request (hyper's default).
pub const MAX_HEADERS: usize = 100;
/// How long a client may take to send its request head (a stalled one holds a thread).
pub const HEAD_TIMEOUT: Duration = Duration::from_secs(10);
/// After refusing a request whose head was not read whole, what is still coming is read and
/// dropped for this long (at most [`DRAIN_MAX_BYTES`]) before the connection closes, so the
/// client reads the answer rather than a reset.
pub const DRAIN_TIME: Duration = Duration::from_secs(2);
pub const DRAIN_MAX_BYTES: usize = 64 * 1024 * 1024;

/// Why a request head was refused (or not read).
#[derive(Debug, thiserror::Error)]
pub enum HeadError {
    #[error("request line over {MAX_REQUEST_LINE} bytes")]
    LineTooLong,
    #[error("request head over {MAX_HEAD_BYTES} bytes")]
    HeadTooLarge,
    #[error("over {MAX_HEADERS} headers")]
    TooManyHeaders,
    #[error("malformed request: {0}")]
    Malformed(String),
    /// The client closed or stalled before the head was whole: nothing to answer.
    #[error("no request: {0}")]
    Io(#[from] std::io::Error),
}

impl HeadError {
    /// The status that answers it (None: the connection is just closed).
    pub fn status(&self) -> Option<u16> {
        match self {
            HeadError::LineTooLong => Some(414),
            HeadError::HeadTooLarge | HeadError::TooManyHeaders => Some(431),
            HeadError::Malformed(_) => Some(400),
            HeadError::Io(_) => None,
        }
    }
}

/// A request's head.
#[derive(Debug, Clone)]
pub struct Request {
    pub method: String,
    /// The request target: path and query ("/api/frames?from=0&to=10").
    pub target: String,
    /// (name in lower case, value).
    headers: Vec<(String, String)>,
}

impl Request {
    /// The value of header `name` (any case); None when absent, or when given more than once
    /// (a request that repeats Host or Origin is not trusted with either).
    pub fn header(&self, name: &str) -> Option<&str> {
        let mut it = self
            .headers
            .iter()
            .filter(|(k, _)| k.eq_ignore_ascii_case(name));
        match (it.next(), it.next()) {
            (Some((_, v)), None) => Some(v.as_str()),
            _ => None,
        }
    }
    /// Whether header `name` is there at all (once or more).
    pub fn has_header(&self, name: &str) -> bool {
        self.headers
            .iter()
            .any(|(k, _)| k.eq_ignore_ascii_case(name))
    }
    /// The target's path (before `?`).
    pub fn path(&self) -> &str {
        self.target.split('?').next().unwrap_or("/")
    }
}

/// Parses a whole head (ending in an empty line).
pub fn parse_head(head: &[u8]) -> Result<Request, HeadError> {
    let line_end = head.windows(2).position(|w| w == b"\r\n");
    if line_end.unwrap_or(head.len()) > MAX_REQUEST_LINE {
        return Err(HeadError::LineTooLong);
    }
    let mut slots = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut slots);
    match req.parse(head) {
        Ok(httparse::Status::Complete(_)) => {}
        Ok(httparse::Status::Partial) => return Err(HeadError::Malformed("head cut short".into())),
        Err(httparse::Error::TooManyHeaders) => return Err(HeadError::TooManyHeaders),
        Err(e) => return Err(HeadError::Malformed(e.to_string())),
    }
    let headers = req
        .headers
        .iter()
        .map(|h| {
            String::from_utf8(h.value.to_vec())
                .map(|v| (h.name.to_ascii_lowercase(), v))
                .map_err(|_| HeadError::Malformed(format!("header {} is not UTF-8", h.name)))
        })
        .collect::<Result<_, _>>()?;
    Ok(Request {
        method: req.method.unwrap_or("").to_string(),
        target: req.path.unwrap_or("/").to_string(),
        headers,
    })
}

/// Reads one request head from `s` (at most [`MAX_HEAD_BYTES`], within [`HEAD_TIMEOUT`]).
/// A body the request may carry is not read (no route takes one).
pub fn read_request(s: &mut TcpStream) -> Result<Request, HeadError> {
    s.set_read_timeout(Some(HEAD_TIMEOUT))?;
    let start = Instant::now();
    let mut buf = Vec::with_capacity(2048);
    let mut chunk = [0u8; 4096];
    loop {
        if let Some(end) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            s.set_read_timeout(None)?;
            return parse_head(&buf[..end + 4]);
        }
        // A request line longer than the limit is known before the head is over.
        if !buf.windows(2).any(|w| w == b"\r\n") && buf.len() > MAX_REQUEST_LINE {
            return Err(HeadError::LineTooLong);
        }
        if buf.len() >= MAX_HEAD_BYTES {
            return Err(HeadError::HeadTooLarge);
        }
        if start.elapsed() > HEAD_TIMEOUT {
            return Err(HeadError::Io(std::io::ErrorKind::TimedOut.into()));
        }
        let want = chunk.len().min(MAX_HEAD_BYTES - buf.len());
        let n = s.read(&mut chunk[..want])?;
        if n == 0 {
            return Err(HeadError::Io(std::io::ErrorKind::UnexpectedEof.into()));
        }
        buf.extend_from_slice(&chunk[..n]);
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        409 => "Conflict",
        414 => "URI Too Long",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "",
    }
}

/// The status line and headers of a response whose body follows (`len` bytes, or None: up to
/// the connection's end, as a stream of events is).
pub fn head(status: u16, kind: &str, len: Option<usize>) -> String {
    let mut h = format!(
        "HTTP/1.1 {status} {}\r\nContent-Type: {kind}\r\nCache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\nConnection: close\r\n",
        reason(status)
    );
    if let Some(n) = len {
        h.push_str(&format!("Content-Length: {n}\r\n"));
    }
    h.push_str("\r\n");
    h
}

/// Writes a whole response. A client that went away: nothing to do.
pub fn respond(s: &mut TcpStream, status: u16, kind: &str, body: &[u8]) {
    let _ = s
        .write_all(head(status, kind, Some(body.len())).as_bytes())
        .and_then(|_| s.write_all(body))
        .and_then(|_| s.flush());
}

/// Answers a request refused before its head was read whole, then reads and drops what the
/// client still sends (bounded), so it sees the answer.
pub fn refuse_unread(s: &mut TcpStream, status: u16, why: &str) {
    respond(s, status, "text/plain", format!("{why}\n").as_bytes());
    let _ = s.shutdown(Shutdown::Write);
    let _ = s.set_read_timeout(Some(Duration::from_millis(200)));
    let start = Instant::now();
    let mut sink = [0u8; 16 * 1024];
    let mut dropped = 0usize;
    while start.elapsed() < DRAIN_TIME && dropped < DRAIN_MAX_BYTES {
        match s.read(&mut sink) {
            Ok(0) => break,
            Ok(n) => dropped += n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(_) => break,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_head_parses_with_its_headers_and_repeated_ones_are_not_trusted() {
        let r = parse_head(
            b"GET /api/frames?from=3 HTTP/1.1\r\nHost: 127.0.0.1:80\r\nX-A: 1\r\nx-a: 2\r\n\r\n",
        )
        .unwrap();
        assert_eq!((r.method.as_str(), r.path()), ("GET", "/api/frames"));
        assert_eq!(r.target, "/api/frames?from=3");
        assert_eq!(r.header("HOST"), Some("127.0.0.1:80"));
        assert_eq!(r.header("x-a"), None);
        assert!(r.has_header("X-A"));
    }

    #[test]
    fn heads_over_the_limits_are_refused_by_their_status() {
        let long = format!("GET /{} HTTP/1.1\r\n\r\n", "a".repeat(MAX_REQUEST_LINE));
        assert_eq!(parse_head(long.as_bytes()).unwrap_err().status(), Some(414));
        let many = format!(
            "GET / HTTP/1.1\r\n{}\r\n",
            "X: y\r\n".repeat(MAX_HEADERS + 1)
        );
        assert_eq!(parse_head(many.as_bytes()).unwrap_err().status(), Some(431));
        let fine = format!("GET / HTTP/1.1\r\n{}\r\n", "X: y\r\n".repeat(MAX_HEADERS));
        assert!(parse_head(fine.as_bytes()).is_ok());
        assert_eq!(
            parse_head(b"GET\x01 / HTTP/1.1\r\n\r\n")
                .unwrap_err()
                .status(),
            Some(400)
        );
    }
}
