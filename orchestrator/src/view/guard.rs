//! Who may use the viewer (issue 37): the server listens on 127.0.0.1, but any page the
//! user's browser opens can send requests there, and a page of a name rebound to 127.0.0.1
//! (DNS rebinding) would be same-origin with it. So every request is checked:
//!
//! - `Host` must name this server: `127.0.0.1:PORT` or `localhost:PORT` (a rebound name is
//!   refused, so a rebinding page reads nothing);
//! - `Origin`, when the browser sends one, must be this server's own origin;
//! - `Sec-Fetch-Site`, when sent, must say the request came from the viewer's own page
//!   (`same-origin`) or from the user (`none`: the address bar), except for opening the page
//!   from a link (a navigation GET). A page on another local port is `same-site`, not
//!   same-origin: it cannot even include `/run.js` as a script and read the run;
//! - the kill (`POST /api/kill`) needs all of this, an `Origin`, and the server's secret token
//!   in the `X-Swarm-Token` header: a random 128-bit value made when the server starts and
//!   written only into the page (`GET /`), which no other origin can read. A custom header
//!   cannot be sent cross-origin without a CORS preflight, which this server never approves.

use super::http::Request;
use rand::RngCore;

/// The header that carries the kill token.
pub const TOKEN_HEADER: &str = "X-Swarm-Token";

/// Why a request was refused (answered 403 with this text).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refused {
    /// The Host header given ("(none)", "(repeated)").
    #[error("Host {0:?} is not this viewer's (allowed: 127.0.0.1:PORT, localhost:PORT)")]
    Host(String),
    #[error("Origin {0:?} is not this viewer's")]
    Origin(String),
    #[error("Sec-Fetch-Site {0:?}: only the viewer's own page may ask this")]
    FetchSite(String),
    #[error("a kill needs the viewer page's Origin")]
    NoOrigin,
    #[error("a kill needs the viewer page's token ({TOKEN_HEADER})")]
    Token,
}

/// The checks of one server (its port and token).
#[derive(Debug, Clone)]
pub struct Guard {
    port: u16,
    token: String,
}

/// Equal strings, compared in a time that does not depend on where they differ.
fn same_secret(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

impl Guard {
    /// A guard for the server on `port` with a fresh random token.
    pub fn new(port: u16) -> Guard {
        let mut bytes = [0u8; 16];
        rand::rngs::OsRng.fill_bytes(&mut bytes);
        Guard::with_token(port, bytes.iter().map(|b| format!("{b:02x}")).collect())
    }

    pub fn with_token(port: u16, token: String) -> Guard {
        Guard { port, token }
    }

    /// The token the page sends with a kill (it goes into the page only).
    pub fn token(&self) -> &str {
        &self.token
    }

    fn own_host(&self, host: &str) -> bool {
        let port = format!(":{}", self.port);
        host.strip_suffix(&port)
            .is_some_and(|h| h == "127.0.0.1" || h.eq_ignore_ascii_case("localhost"))
    }

    /// Whether `r` may be answered at all.
    pub fn check(&self, r: &Request) -> Result<(), Refused> {
        match r.header("host") {
            Some(h) if self.own_host(h) => {}
            Some(h) => return Err(Refused::Host(h.to_string())),
            None if r.has_header("host") => return Err(Refused::Host("(repeated)".into())),
            None => return Err(Refused::Host("(none)".into())),
        }
        if r.has_header("origin") {
            match r.header("origin") {
                Some(o) if o.strip_prefix("http://").is_some_and(|h| self.own_host(h)) => {}
                o => return Err(Refused::Origin(o.unwrap_or("(repeated)").to_string())),
            }
        }
        if let Some(site) = r.header("sec-fetch-site") {
            let navigation = r.method == "GET" && r.header("sec-fetch-mode") == Some("navigate");
            if !matches!(site, "same-origin" | "none") && !navigation {
                return Err(Refused::FetchSite(site.to_string()));
            }
        }
        Ok(())
    }

    /// Whether `r` (which passed [`check`](Guard::check)) may kill: it has an Origin (a
    /// browser always sends one with a POST, and `check` found it is the page's) and the
    /// token.
    pub fn check_kill(&self, r: &Request) -> Result<(), Refused> {
        if r.header("origin").is_none() {
            return Err(Refused::NoOrigin);
        }
        match r.header(TOKEN_HEADER) {
            Some(t) if same_secret(t, &self.token) => Ok(()),
            _ => Err(Refused::Token),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::http::parse_head;

    fn req(lines: &[&str]) -> Request {
        parse_head(format!("{}\r\n\r\n", lines.join("\r\n")).as_bytes()).unwrap()
    }

    #[test]
    fn only_this_servers_host_and_origin_pass() {
        let g = Guard::with_token(8080, "t0k".into());
        assert!(g
            .check(&req(&["GET / HTTP/1.1", "Host: 127.0.0.1:8080"]))
            .is_ok());
        assert!(g
            .check(&req(&["GET / HTTP/1.1", "Host: LocalHost:8080"]))
            .is_ok());
        for bad in [
            "Host: 127.0.0.1:8081",
            "Host: evil.example:8080",
            "Host: 127.0.0.1.evil.example:8080",
            "Host: 127.0.0.1",
        ] {
            let e = g.check(&req(&["GET / HTTP/1.1", bad])).unwrap_err();
            assert!(matches!(e, Refused::Host(_)), "{bad}: {e}");
        }
        assert!(matches!(
            g.check(&req(&["GET / HTTP/1.1"])),
            Err(Refused::Host(h)) if h == "(none)"
        ));
        // Two Host headers: neither is trusted.
        let two = req(&["GET / HTTP/1.1", "Host: 127.0.0.1:8080", "Host: evil:8080"]);
        assert!(g.check(&two).is_err());
        let h = "Host: 127.0.0.1:8080";
        assert!(g
            .check(&req(&[
                "GET / HTTP/1.1",
                h,
                "Origin: http://localhost:8080"
            ]))
            .is_ok());
        for o in [
            "Origin: http://127.0.0.1:9999",
            "Origin: null",
            "Origin: https://127.0.0.1:8080",
        ] {
            let e = g
                .check(&req(&["POST /api/kill HTTP/1.1", h, o]))
                .unwrap_err();
            assert!(matches!(e, Refused::Origin(_)), "{o}: {e}");
        }
    }

    #[test]
    fn other_sites_may_open_the_page_but_not_fetch_from_it() {
        let g = Guard::with_token(80, "t".into());
        let h = "Host: localhost:80";
        let nav = ["Sec-Fetch-Site: cross-site", "Sec-Fetch-Mode: navigate"];
        assert!(g
            .check(&req(&["GET / HTTP/1.1", h, nav[0], nav[1]]))
            .is_ok());
        assert!(g
            .check(&req(&["POST /api/kill HTTP/1.1", h, nav[0], nav[1]]))
            .is_err());
        for site in ["same-site", "cross-site"] {
            let s = format!("Sec-Fetch-Site: {site}");
            let r = req(&["GET /run.js HTTP/1.1", h, &s, "Sec-Fetch-Mode: no-cors"]);
            assert_eq!(g.check(&r), Err(Refused::FetchSite(site.into())));
        }
        let own = req(&["GET /run.js HTTP/1.1", h, "Sec-Fetch-Site: same-origin"]);
        assert!(g.check(&own).is_ok());
    }

    #[test]
    fn a_kill_needs_the_origin_and_the_exact_token() {
        let g = Guard::new(80);
        let (h, o) = ("Host: 127.0.0.1:80", "Origin: http://127.0.0.1:80");
        let t = format!("X-Swarm-Token: {}", g.token());
        assert_eq!(g.token().len(), 32);
        assert_ne!(g.token(), Guard::new(80).token());
        assert!(g
            .check_kill(&req(&["POST /api/kill HTTP/1.1", h, o, &t]))
            .is_ok());
        assert_eq!(
            g.check_kill(&req(&["POST /api/kill HTTP/1.1", h, &t])),
            Err(Refused::NoOrigin)
        );
        assert_eq!(
            g.check_kill(&req(&["POST /api/kill HTTP/1.1", h, o])),
            Err(Refused::Token)
        );
        let wrong = format!("X-Swarm-Token: {}0", g.token());
        assert_eq!(
            g.check_kill(&req(&["POST /api/kill HTTP/1.1", h, o, &wrong])),
            Err(Refused::Token)
        );
        let twice = format!("{t}\r\n{t}");
        assert_eq!(
            g.check_kill(&req(&["POST /api/kill HTTP/1.1", h, o, &twice])),
            Err(Refused::Token)
        );
    }
}
