//! Who may use the live viewer (issue 37, item 3), against a real `up --view` run with real
//! agent processes: a forged Host (a DNS-rebinding page's) is refused; a request line of
//! 10 MB and 20,000 headers are refused; a kill without the page's token, with a wrong one,
//! or without the page's Origin is refused; a page served from another local port, opened in
//! headless Chromium, tries the kill (and to read the run through `/run.js`) and fails: the
//! robot lives. The page's own kill button, clicked with a real mouse event, still kills.

mod browser;

use browser::cdp::Browser;
use browser::*;
use e2e::*;
use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::mpsc::channel;
use std::time::{Duration, Instant};

/// Robot the attacks aim at (it must live) and the one the page's button kills.
const TARGET: u32 = 1;
const BUTTON: u32 = 2;

/// Whether robot `r` is alive in the newest frame.
fn alive_now(url: &str, r: usize) -> bool {
    let frames = json(url, "/api/frames");
    let last = frames.as_array().unwrap().last().unwrap().clone();
    last["alive"][r] == 1
}

/// Sends `head` (its bytes may be many) on a new connection and reads the answer; a server
/// that refuses early may close before all is written (the write error is not the test's).
fn send_raw(url: &str, head: Vec<u8>) -> (u16, String) {
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    let mut w = s.try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        let _ = w.write_all(&head);
    });
    let got = read_response(s);
    let _ = writer.join();
    got
}

/// A page on another local port (the attacker's): it tries the kill with `fetch` (no-cors,
/// and with a guessed token header, which needs CORS), includes the viewer's `/run.js` as a
/// script to read the run, then reports what it saw to its own server. The report's text.
fn attack_from_another_port(viewer: &str) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let me = format!("http://{}/", listener.local_addr().unwrap());
    let v = viewer.trim_end_matches('/');
    let page = format!(
        r#"<!doctype html><html><body><pre id="state">attack</pre><script>
const V = "{v}", out = [];
fetch(V + "/api/kill?robot={TARGET}", {{method: "POST", mode: "no-cors"}})
  .then(() => out.push("no-cors sent"), (e) => out.push("no-cors error"))
  .then(() => fetch(V + "/api/kill?robot={TARGET}", {{method: "POST", headers: {{"X-Swarm-Token": "00"}}}}))
  .then((r) => out.push("cors " + r.status), () => out.push("cors refused"))
  .then(() => new Promise((done) => {{
    const s = document.createElement("script");
    s.src = V + "/run.js";
    s.onload = () => done("loaded"); s.onerror = () => done("refused");
    document.head.appendChild(s);
  }}))
  .then((x) => out.push("run.js " + x + ", RUN " + typeof window.RUN))
  .then(() => fetch("/report?" + encodeURIComponent(out.join("; "))));
</script></body></html>"#
    );
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for conn in listener.incoming() {
            let Ok(mut s) = conn else { return };
            let mut line = String::new();
            let mut r = BufReader::new(s.try_clone().unwrap());
            if r.read_line(&mut line).is_err() {
                continue;
            }
            let path = line.split_whitespace().nth(1).unwrap_or("/").to_string();
            let body = if let Some(report) = path.strip_prefix("/report?") {
                let _ = tx.send(report.to_string());
                "ok".to_string()
            } else {
                page.clone()
            };
            let _ = write!(
                s,
                "HTTP/1.1 200 OK\r\nContent-Type: text/html\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
                body.len()
            );
        }
    });
    let b = Browser::open_page(&me, 800, 600, "attacker", "true");
    let report = rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the attacker's page never reported");
    drop(b);
    percent_decoded(&report)
}

/// `s` with its %XX escapes decoded.
fn percent_decoded(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let hex = (b[k] == b'%' && k + 2 < b.len())
            .then(|| std::str::from_utf8(&b[k + 1..k + 3]).ok())
            .flatten()
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match hex {
            Some(v) => {
                out.push(v);
                k += 3;
            }
            None => {
                out.push(b[k]);
                k += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[test]
fn only_the_viewers_own_page_may_kill_and_the_attacks_leave_the_robot_alive() {
    let _g = serial();
    chromium();
    let out = tmp_dir("view-guard");
    let id = own_run_id("view-guard");
    let mut child = spawn_up_as(
        &[
            "--view",
            "--scenario",
            roam(),
            "--robots",
            "6",
            // 30 s: every attack and the button's kill happen while it runs (they took 12 s
            // at load 12).
            "--max-ticks",
            "900",
            "--tick-hz",
            "30",
            "--seed",
            "2",
        ],
        &out,
        Some(&id),
    );
    let url = viewer_url(&mut child);
    let t = Instant::now();
    while json(&url, "/api/frames").as_array().unwrap().len() < 5 {
        assert!(t.elapsed() < Duration::from_secs(60), "no frames");
        std::thread::sleep(Duration::from_millis(50));
    }
    let addr = url.trim_start_matches("http://").trim_end_matches('/');
    let port = addr.rsplit(':').next().unwrap();
    let origin = url.trim_end_matches('/').to_string();
    let token = page_token(&url);
    let kill = format!("/api/kill?robot={TARGET}");

    // A forged Host (a rebound name): nothing is answered, not even the page.
    let evil = format!("evil.example:{port}");
    for path in ["/", "/api/meta", "/run.js"] {
        let (status, body) = http_with("GET", &url, path, &[("Host", &evil)]);
        assert_eq!(status, 403, "{path}: {body}");
    }
    let (status, body) = http_with(
        "POST",
        &url,
        &kill,
        &[
            ("Host", &evil),
            ("Origin", &origin),
            ("X-Swarm-Token", &token),
        ],
    );
    assert_eq!(status, 403, "{body}");
    let (status, _) = http_with(
        "GET",
        &url,
        "/api/meta",
        &[("Host", &format!("localhost:{port}"))],
    );
    assert_eq!(status, 200);

    // Heads over the limits: a 10 MB request line, 20,000 headers.
    let mut long = b"GET /".to_vec();
    long.extend(std::iter::repeat_n(b'a', 10 << 20));
    long.extend(format!(" HTTP/1.1\r\nHost: {addr}\r\n\r\n").bytes());
    assert_eq!(send_raw(&url, long).0, 414);
    let mut many = format!("GET /api/meta HTTP/1.1\r\nHost: {addr}\r\n").into_bytes();
    for k in 0..20_000 {
        many.extend(format!("X-H{k}: v\r\n").bytes());
    }
    many.extend(b"\r\n");
    assert_eq!(send_raw(&url, many).0, 431);
    let mut some = format!("GET /api/meta HTTP/1.1\r\nHost: {addr}\r\n").into_bytes();
    for k in 0..150 {
        some.extend(format!("X{k}: v\r\n").bytes());
    }
    some.extend(b"\r\n");
    assert_eq!(send_raw(&url, some).0, 431, "150 headers");
    assert_eq!(
        http("GET", &url, "/api/meta").0,
        200,
        "the server still serves"
    );

    // Kills without the page's token, with a wrong one, without its Origin, from another.
    let wrong = format!("{}0", &token[1..]);
    let other = "http://127.0.0.1:1".to_string();
    for (what, headers) in [
        ("no token", vec![("Origin", origin.as_str())]),
        (
            "a wrong token",
            vec![
                ("Origin", origin.as_str()),
                ("X-Swarm-Token", wrong.as_str()),
            ],
        ),
        ("no Origin", vec![("X-Swarm-Token", token.as_str())]),
        (
            "another Origin",
            vec![
                ("Origin", other.as_str()),
                ("X-Swarm-Token", token.as_str()),
            ],
        ),
    ] {
        let (status, body) = http_with("POST", &url, &kill, &headers);
        assert_eq!(status, 403, "a kill with {what}: {body}");
    }

    // A page on another local port in a real browser.
    let report = attack_from_another_port(&url);
    assert!(report.contains("no-cors sent"), "{report}");
    assert!(report.contains("cors refused"), "{report}");
    assert!(
        report.contains("RUN undefined"),
        "the attacker read the run: {report}"
    );
    // A kill that got through would show within a few ticks (30 ticks/s).
    std::thread::sleep(Duration::from_millis(700));
    assert!(
        alive_now(&url, TARGET as usize),
        "robot {TARGET} died: {report}"
    );

    // The page's own button, clicked.
    let mut b = Browser::open(&format!("{url}?robot={BUTTON}"), 1280, 720, "button");
    b.wait_for("!document.getElementById('kill').disabled");
    b.click_on("#kill");
    b.wait_for(&format!(
        "document.getElementById('killmsg').textContent.includes('killed robot {BUTTON}')"
    ));
    drop(b);
    let t = Instant::now();
    while alive_now(&url, BUTTON as usize) {
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "robot {BUTTON} never died"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["end"], "completed", "{s}");
    let faults = s["faults"].as_array().unwrap();
    let robots: Vec<u64> = faults
        .iter()
        .map(|f| f["robot"].as_u64().unwrap())
        .collect();
    assert_eq!(robots, vec![BUTTON as u64], "{s}");
    assert_left_nothing(&out);
}
