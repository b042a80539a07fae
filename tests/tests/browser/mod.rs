//! What the viewer's browser tests share: headless Chromium (screenshots and the page's
//! `#state` without a driver; `cdp`: real mouse input over the DevTools pipe), the page's
//! projection of the arena, raw HTTP to the viewer, the checks of robots in a screenshot.
#![allow(dead_code)]

pub mod cdp;

use e2e::*;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub fn configs() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// The page's projection (orchestrator/src/view/page/viewer.js): the canvas fills the window
/// left of the side panel (`SIDE_W` px; at least `MIN_CANVAS` px each way), from the page's
/// top-left corner; at zoom 1 the arena fits it less `MARGIN` px on each side, centred; y
/// up. The view is the zoom over that fit and the arena point at the canvas's centre.
pub const SIDE_W: f64 = 400.0;
pub const MIN_CANVAS: f64 = 200.0;
pub const MARGIN: f64 = 10.0;
/// The window of the tests' screenshots (unless they say otherwise).
pub const WINDOW: (u32, u32) = (1200, 820);
/// A robot's disc radius on the page, in pixels, at any zoom.
pub const ROBOT_PX: f64 = 5.0;
/// Robots closer than this on the page are not checked (their discs may cover each other).
pub const CLEAR_PX: f64 = 14.0;

/// A window and the page's view in it.
#[derive(Debug, Clone, Copy)]
pub struct View {
    pub window: (u32, u32),
    pub zoom: f64,
    /// The arena point at the canvas's centre (None: the arena's centre).
    pub centre: Option<[f64; 2]>,
}

impl View {
    /// The whole arena in a window of `w` x `h`.
    pub fn fit(w: u32, h: u32) -> View {
        View {
            window: (w, h),
            zoom: 1.0,
            centre: None,
        }
    }
    /// The canvas's size.
    pub fn canvas(&self) -> (f64, f64) {
        (
            (self.window.0 as f64 - SIDE_W).max(MIN_CANVAS),
            (self.window.1 as f64).max(MIN_CANVAS),
        )
    }
    /// Pixels per arena unit.
    pub fn scale(&self, meta: &serde_json::Value) -> f64 {
        let (aw, ah) = arena(meta);
        let (w, h) = self.canvas();
        ((w - 2.0 * MARGIN) / aw).min((h - 2.0 * MARGIN) / ah) * self.zoom
    }
    /// Page pixel of arena point `p`.
    pub fn project(&self, meta: &serde_json::Value, p: [f64; 2]) -> (f64, f64) {
        let (aw, ah) = arena(meta);
        let c = self.centre.unwrap_or([aw / 2.0, ah / 2.0]);
        let (w, h) = self.canvas();
        let s = self.scale(meta);
        (w / 2.0 + (p[0] - c[0]) * s, h / 2.0 - (p[1] - c[1]) * s)
    }
}

/// The arena's width and height.
pub fn arena(meta: &serde_json::Value) -> (f64, f64) {
    (
        meta["arena"][0].as_f64().unwrap(),
        meta["arena"][1].as_f64().unwrap(),
    )
}

/// Page pixel of arena point `p` in the tests' window with the whole arena in view.
pub fn project(meta: &serde_json::Value, p: [f64; 2]) -> (f64, f64) {
    View::fit(WINDOW.0, WINDOW.1).project(meta, p)
}

/// The arguments of every Chromium run.
pub const CHROMIUM_ARGS: &[&str] = &[
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
];

pub fn chromium() -> PathBuf {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("chromium"))
            .find(|p| p.is_file())
    });
    found.unwrap_or_else(|| {
        panic!(
            "the viewer tests need a real browser: `chromium` is not on PATH. Install it \
             (Debian: apt-get install -y chromium; .ci/run does so when it is missing)"
        )
    })
}

/// How long one Chromium run may take: 3-5 s even at load 40. Headless Chromium with
/// `--virtual-time-budget` sometimes never ends: 1 of 30 runs of the played page against a
/// live `orchestrator view` at load 40-57 (2026-12-02 06:00 UTC), while the server answered
/// the next run at once. So a run over the limit is killed and tried again, a fresh profile
/// each time, up to [`CHROMIUM_TRIES`] times; the page's state is judged as before. 30 s, not
/// the 90 of before: a hang was seen again on an idle machine (2026-12-04, 1 of 6 manual runs of
/// the played page took 341 s), and each costs the suite the whole limit; 30 s is still six
/// times the slowest run measured.
pub const CHROMIUM_LIMIT: Duration = Duration::from_secs(30);
pub const CHROMIUM_TRIES: usize = 3;

/// Runs headless Chromium on `url` with `extra` arguments (window `w` x `h`, a profile of its
/// own); its stdout.
pub fn run_chromium(url: &str, w: u32, h: u32, tag: &str, extra: &[String]) -> (PathBuf, Vec<u8>) {
    for attempt in 1..=CHROMIUM_TRIES {
        if let Some(out) = run_chromium_once(url, w, h, &format!("{tag}-{attempt}"), extra) {
            return out;
        }
        eprintln!(
            "chromium took over {CHROMIUM_LIMIT:?} for {url} (try {attempt} of {CHROMIUM_TRIES})"
        );
    }
    panic!("chromium took over {CHROMIUM_LIMIT:?} for {url}, {CHROMIUM_TRIES} times");
}

/// One Chromium run; None when it took over [`CHROMIUM_LIMIT`] (killed).
pub fn run_chromium_once(
    url: &str,
    w: u32,
    h: u32,
    tag: &str,
    extra: &[String],
) -> Option<(PathBuf, Vec<u8>)> {
    let dir = tmp_dir(&format!("chromium-{tag}"));
    std::fs::create_dir_all(&dir).unwrap();
    let mut c = Command::new(chromium())
        .args(CHROMIUM_ARGS)
        .arg(format!("--user-data-dir={}", dir.join("profile").display()))
        .args(extra)
        .arg(format!("--window-size={w},{h}"))
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromium");
    let mut out = c.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    let t = Instant::now();
    while c.try_wait().unwrap().is_none() {
        if t.elapsed() > CHROMIUM_LIMIT {
            let _ = c.kill();
            let _ = c.wait();
            let _ = reader.join();
            let _ = std::fs::remove_dir_all(&dir);
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Some((dir, reader.join().unwrap()))
}

/// A screenshot of `url` (window `w` x `h`), decoded: (width, RGB rows).
pub fn screenshot(url: &str, w: u32, h: u32, tag: &str) -> Shot {
    let shots = tmp_dir(&format!("shot-{tag}"));
    std::fs::create_dir_all(&shots).unwrap();
    let file = shots.join("shot.png");
    let (dir, _) = run_chromium(
        url,
        w,
        h,
        tag,
        &[format!("--screenshot={}", file.display())],
    );
    let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("no screenshot of {url}: {e}"));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&shots);
    Shot::decode(&bytes)
}

/// The page's own state after `budget_ms` of virtual time (its `#state` element, JSON: the
/// tick shown, the frames it holds, the marks it drew, what the selected robot heard).
pub fn page_state(url: &str, budget_ms: u32, tag: &str) -> serde_json::Value {
    let (dir, dom) = run_chromium(
        url,
        1200,
        820,
        tag,
        &[
            "--dump-dom".to_string(),
            format!("--virtual-time-budget={budget_ms}"),
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
    let dom = String::from_utf8_lossy(&dom);
    let start = dom
        .find("<pre id=\"state\" hidden=\"\">")
        .unwrap_or_else(|| panic!("no #state in the page of {url}: {dom}"));
    let body = &dom[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</pre>").unwrap()];
    let body = body
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&body).unwrap_or_else(|e| panic!("#state of {url}: {e}: {body}"))
}

pub struct Shot {
    pub width: usize,
    pub height: usize,
    channels: usize,
    data: Vec<u8>,
}

impl Shot {
    pub fn decode(bytes: &[u8]) -> Shot {
        let mut dec = png::Decoder::new(bytes);
        dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut r = dec.read_info().unwrap();
        let mut data = vec![0; r.output_buffer_size()];
        let info = r.next_frame(&mut data).unwrap();
        data.truncate(info.buffer_size());
        Shot {
            width: info.width as usize,
            height: info.height as usize,
            channels: info.color_type.samples(),
            data,
        }
    }
    pub fn rgb(&self, x: f64, y: f64) -> [u8; 3] {
        let (x, y) = (x.round() as usize, y.round() as usize);
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) off the screenshot"
        );
        let i = (y * self.width + x) * self.channels;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
    pub fn differing_pixels(&self, o: &Shot) -> usize {
        self.data
            .chunks(self.channels)
            .zip(o.data.chunks(o.channels))
            .filter(|(a, b)| a[..3] != b[..3])
            .count()
    }
}

pub fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (*x as i32 - y as i32).abs() <= 3)
}

/// GET (or POST) `path` of the server at `base` ("http://127.0.0.1:P/"): (status, body).
pub fn http(method: &str, base: &str, path: &str) -> (u16, String) {
    http_with(method, base, path, &[])
}

/// [`http`] with more headers (`Host` is the server's own unless `extra` gives one).
pub fn http_with(method: &str, base: &str, path: &str, extra: &[(&str, &str)]) -> (u16, String) {
    let addr = base.trim_start_matches("http://").trim_end_matches('/');
    let mut s = TcpStream::connect(addr).expect("connect to the viewer");
    let mut head = format!("{method} {path} HTTP/1.1\r\n");
    if !extra.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        head.push_str(&format!("Host: {addr}\r\n"));
    }
    for (k, v) in extra {
        head.push_str(&format!("{k}: {v}\r\n"));
    }
    head.push_str("Connection: close\r\nContent-Length: 0\r\n\r\n");
    s.write_all(head.as_bytes()).unwrap();
    read_response(s)
}

/// The (status, body) of the response on `s` (read to its end).
pub fn read_response(mut s: TcpStream) -> (u16, String) {
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let raw = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = raw.split_once("\r\n\r\n").expect("an HTTP response");
    let status = head.split(' ').nth(1).unwrap().parse().unwrap();
    // Chunked bodies: join the chunks.
    let body = if head
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        let mut out = String::new();
        let mut rest = body;
        loop {
            let (len, tail) = rest.split_once("\r\n").unwrap();
            let n = usize::from_str_radix(len.trim(), 16).unwrap();
            if n == 0 {
                break;
            }
            out.push_str(&tail[..n]);
            rest = &tail[n + 2..];
        }
        out
    } else {
        body.to_string()
    };
    (status, body)
}

/// The kill token in the viewer's page (its `<meta name="swarm-kill-token">`).
pub fn page_token(base: &str) -> String {
    let (status, page) = http("GET", base, "/");
    assert_eq!(status, 200, "{page}");
    let at = page
        .find("name=\"swarm-kill-token\" content=\"")
        .unwrap_or_else(|| panic!("no token in the page: {page}"));
    let rest = &page[at + "name=\"swarm-kill-token\" content=\"".len()..];
    rest[..rest.find('"').unwrap()].to_string()
}

/// The kill POST as the viewer's page sends it (its Origin and token): (status, body).
pub fn kill_as_the_page(base: &str, robot: u32) -> (u16, String) {
    let origin = base.trim_end_matches('/');
    let token = page_token(base);
    http_with(
        "POST",
        base,
        &format!("/api/kill?robot={robot}"),
        &[("Origin", origin), ("X-Swarm-Token", &token)],
    )
}

pub fn json(base: &str, path: &str) -> serde_json::Value {
    let (status, body) = http("GET", base, path);
    assert_eq!(status, 200, "{path}: {body}");
    serde_json::from_str(&body).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Reads the first stdout line of `child`, which names the viewer's URL; the rest of its
/// output is read (and dropped) on a thread, so the child never writes into a closed pipe.
pub fn viewer_url(child: &mut Child) -> String {
    let mut out = BufReader::new(child.stdout.take().expect("piped stdout"));
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::sink()));
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("no URL in {line:?}"));
    url.to_string()
}

/// `orchestrator view DIR` in the background; its URL.
pub struct ViewServer {
    child: Child,
    pub url: String,
}

impl ViewServer {
    /// The page asks for `chunk` ticks at a time (0: the server's choice by size).
    pub fn start(dir: &Path, chunk: usize) -> ViewServer {
        let mut child = Command::new(orchestrator())
            .arg("view")
            .arg(dir)
            .args(["--chunk", &chunk.to_string()])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let url = viewer_url(&mut child);
        ViewServer { child, url }
    }
}

impl Drop for ViewServer {
    fn drop(&mut self) {
        // SAFETY: Ctrl-C to the viewer this test started.
        unsafe { libc::kill(self.child.id() as i32, libc::SIGINT) };
        let _ = self.child.wait();
    }
}

pub fn pose(f: &serde_json::Value, i: usize) -> [f64; 2] {
    let p = &f["poses"][i];
    [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()]
}

/// The colour the page fills robot `i` with in frame `f`: its display state's, as the meta
/// names it; with no states (roam), robot i of n has hue i / n (saturation 0.65, lightness
/// 0.45), as run.svg colours robots.
pub fn robot_colour(meta: &serde_json::Value, f: &serde_json::Value, i: usize) -> [u8; 3] {
    let st = f["states"][i].as_u64().unwrap();
    let states = meta["states"].as_array().unwrap();
    if states.is_empty() {
        let n = meta["robots"].as_u64().unwrap().max(1) as f64;
        let (h, s, l) = (i as f64 / n * 6.0, 0.65, 0.45);
        let c = (1.0 - (2.0 * l - 1.0f64).abs()) * s;
        let x = c * (1.0 - (h % 2.0 - 1.0).abs());
        let m = l - c / 2.0;
        let t = [
            [c, x, 0.0],
            [x, c, 0.0],
            [0.0, c, x],
            [0.0, x, c],
            [x, 0.0, c],
            [c, 0.0, x],
        ][(h.floor() as usize).min(5)];
        return t.map(|v| ((v + m) * 255.0).floor() as u8);
    }
    let d = states
        .iter()
        .find(|d| d["state"].as_u64() == Some(st))
        .unwrap_or(&states[0]);
    let c = &d["colour"];
    [0, 1, 2].map(|k| c[k].as_u64().unwrap() as u8)
}

/// Checks the screenshot of frame `f` shows each robot clear of the others where the frame
/// puts it: a live one filled with its state's colour (the pixel 2.5 px behind its centre,
/// clear of its heading line), a dead one's black cross at its centre. Returns how many were
/// checked.
pub fn check_robots(shot: &Shot, meta: &serde_json::Value, f: &serde_json::Value) -> usize {
    check_robots_in(shot, meta, f, View::fit(WINDOW.0, WINDOW.1))
}

/// [`check_robots`] in view `v`.
pub fn check_robots_in(
    shot: &Shot,
    meta: &serde_json::Value,
    f: &serde_json::Value,
    v: View,
) -> usize {
    let (checked, wrong) = compare_robots_in(shot, meta, f, v);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    checked
}

/// (robots checked, what differs) of [`check_robots`].
pub fn compare_robots(
    shot: &Shot,
    meta: &serde_json::Value,
    f: &serde_json::Value,
) -> (usize, Vec<String>) {
    compare_robots_in(shot, meta, f, View::fit(WINDOW.0, WINDOW.1))
}

/// [`compare_robots`] in view `v`.
pub fn compare_robots_in(
    shot: &Shot,
    meta: &serde_json::Value,
    f: &serde_json::Value,
    v: View,
) -> (usize, Vec<String>) {
    let mut wrong = Vec::new();
    let n = f["poses"].as_array().unwrap().len();
    let at: Vec<(f64, f64)> = (0..n).map(|i| v.project(meta, pose(f, i))).collect();
    let (cw, ch) = v.canvas();
    let mut checked = 0;
    for i in 0..n {
        let clear = (0..n).all(|j| {
            j == i || ((at[i].0 - at[j].0).powi(2) + (at[i].1 - at[j].1).powi(2)).sqrt() > CLEAR_PX
        });
        let (x, y) = at[i];
        let inside = x > ROBOT_PX + 1.0
            && y > ROBOT_PX + 1.0
            && x < cw - ROBOT_PX - 1.0
            && y < ch.min(shot.height as f64) - ROBOT_PX - 1.0;
        if !clear || !inside {
            continue;
        }
        if f["alive"][i] == 1 {
            let h = f["poses"][i][2].as_f64().unwrap();
            let (bx, by) = (x - 2.5 * h.cos(), y + 2.5 * h.sin());
            let want = robot_colour(meta, f, i);
            let got = shot.rgb(bx, by);
            if !close(got, want) {
                wrong.push(format!(
                    "tick {}: robot {i} at page ({bx:.1}, {by:.1}): colour {got:?}, want {want:?}",
                    f["tick"]
                ));
            }
        } else {
            let got = shot.rgb(x, y);
            if !got.iter().all(|&c| c < 60) {
                wrong.push(format!(
                    "tick {}: dead robot {i} at page ({x:.1}, {y:.1}): colour {got:?}, want black",
                    f["tick"]
                ));
            }
        }
        checked += 1;
    }
    (checked, wrong)
}

/// Whether a pixel within 1 px of `at` has colour `c` (within 40 a channel: lines are
/// anti-aliased).
pub fn near_colour(shot: &Shot, at: (f64, f64), c: [u8; 3]) -> bool {
    (-1..=1).any(|dx| {
        (-1..=1).any(|dy| {
            let got = shot.rgb(at.0 + dx as f64, at.1 + dy as f64);
            got.iter()
                .zip(c)
                .all(|(x, y)| (*x as i32 - y as i32).abs() <= 40)
        })
    })
}
