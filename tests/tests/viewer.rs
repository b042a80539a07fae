//! The viewer in a real browser (headless Chromium, screenshots without a JS driver) and the
//! exports: the replay page draws every robot where the recording puts it, the scrubber's tick
//! moves the picture, the live page of a running run shows its ticks, a kill by the page's POST
//! is a fault in the summary, the CSV holds the recording's numbers and the MCAP reads back
//! with the same message count.
//!
//! Needs `chromium` on PATH (.ci/run installs Debian's package): a test that does not find it
//! fails, it does not skip.

use e2e::*;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn configs() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs")
}

/// The page's projection (orchestrator/src/view/page/viewer.js): the arena fills the canvas
/// (at the page's top-left corner) `CANVAS_W` pixels wide less `MARGIN` on each side, y up.
const CANVAS_W: f64 = 800.0;
const MARGIN: f64 = 10.0;
/// A robot's disc radius on the page, in pixels.
const ROBOT_PX: f64 = 5.0;
/// Robots closer than this on the page are not checked (their discs may cover each other).
const CLEAR_PX: f64 = 14.0;

fn project(meta: &serde_json::Value, p: [f64; 2]) -> (f64, f64) {
    let w = meta["arena"][0].as_f64().unwrap();
    let h = meta["arena"][1].as_f64().unwrap();
    let s = (CANVAS_W - 2.0 * MARGIN) / w;
    (MARGIN + p[0] * s, MARGIN + (h - p[1]) * s)
}

fn chromium() -> PathBuf {
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
const CHROMIUM_LIMIT: Duration = Duration::from_secs(30);
const CHROMIUM_TRIES: usize = 3;

/// Runs headless Chromium on `url` with `extra` arguments (window `w` x `h`, a profile of its
/// own); its stdout.
fn run_chromium(url: &str, w: u32, h: u32, tag: &str, extra: &[String]) -> (PathBuf, Vec<u8>) {
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
fn run_chromium_once(
    url: &str,
    w: u32,
    h: u32,
    tag: &str,
    extra: &[String],
) -> Option<(PathBuf, Vec<u8>)> {
    let dir = tmp_dir(&format!("chromium-{tag}"));
    std::fs::create_dir_all(&dir).unwrap();
    let mut c = Command::new(chromium())
        .args([
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
        ])
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
fn screenshot(url: &str, w: u32, h: u32, tag: &str) -> Shot {
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
fn page_state(url: &str, budget_ms: u32, tag: &str) -> serde_json::Value {
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

struct Shot {
    width: usize,
    height: usize,
    channels: usize,
    data: Vec<u8>,
}

impl Shot {
    fn decode(bytes: &[u8]) -> Shot {
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
    fn rgb(&self, x: f64, y: f64) -> [u8; 3] {
        let (x, y) = (x.round() as usize, y.round() as usize);
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) off the screenshot"
        );
        let i = (y * self.width + x) * self.channels;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
    fn differing_pixels(&self, o: &Shot) -> usize {
        self.data
            .chunks(self.channels)
            .zip(o.data.chunks(o.channels))
            .filter(|(a, b)| a[..3] != b[..3])
            .count()
    }
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (*x as i32 - y as i32).abs() <= 3)
}

/// GET (or POST) `path` of the server at `base` ("http://127.0.0.1:P/"): (status, body).
fn http(method: &str, base: &str, path: &str) -> (u16, String) {
    let addr = base.trim_start_matches("http://").trim_end_matches('/');
    let mut s = TcpStream::connect(addr).expect("connect to the viewer");
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\nContent-Length: 0\r\n\r\n"
    )
    .unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let raw = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = raw.split_once("\r\n\r\n").expect("an HTTP response");
    let status = head.split(' ').nth(1).unwrap().parse().unwrap();
    // Chunked bodies (tiny_http chunks large ones): join the chunks.
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

fn json(base: &str, path: &str) -> serde_json::Value {
    let (status, body) = http("GET", base, path);
    assert_eq!(status, 200, "{path}: {body}");
    serde_json::from_str(&body).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Reads the first stdout line of `child`, which names the viewer's URL; the rest of its
/// output is read (and dropped) on a thread, so the child never writes into a closed pipe.
fn viewer_url(child: &mut Child) -> String {
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
struct ViewServer {
    child: Child,
    url: String,
}

impl ViewServer {
    /// The page asks for `chunk` ticks at a time (0: the server's choice by size).
    fn start(dir: &Path, chunk: usize) -> ViewServer {
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

fn pose(f: &serde_json::Value, i: usize) -> [f64; 2] {
    let p = &f["poses"][i];
    [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()]
}

/// The colour the page fills robot `i` with in frame `f`: its display state's, as the meta
/// names it; with no states (roam), robot i of n has hue i / n (saturation 0.65, lightness
/// 0.45), as run.svg colours robots.
fn robot_colour(meta: &serde_json::Value, f: &serde_json::Value, i: usize) -> [u8; 3] {
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
fn check_robots(shot: &Shot, meta: &serde_json::Value, f: &serde_json::Value) -> usize {
    let (checked, wrong) = compare_robots(shot, meta, f);
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    checked
}

/// (robots checked, what differs) of [`check_robots`].
fn compare_robots(
    shot: &Shot,
    meta: &serde_json::Value,
    f: &serde_json::Value,
) -> (usize, Vec<String>) {
    let mut wrong = Vec::new();
    let n = f["poses"].as_array().unwrap().len();
    let at: Vec<(f64, f64)> = (0..n).map(|i| project(meta, pose(f, i))).collect();
    let mut checked = 0;
    for i in 0..n {
        let clear = (0..n).all(|j| {
            j == i || ((at[i].0 - at[j].0).powi(2) + (at[i].1 - at[j].1).powi(2)).sqrt() > CLEAR_PX
        });
        let (x, y) = at[i];
        let inside = x > ROBOT_PX + 1.0
            && y > ROBOT_PX + 1.0
            && x < CANVAS_W - ROBOT_PX - 1.0
            && y < shot.height as f64 - ROBOT_PX - 1.0;
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

/// A finished in-process search run (robot 4 killed at tick 30).
fn finished_run(tag: &str) -> PathBuf {
    let out = tmp_dir(tag);
    let sc = configs().join("search.toml");
    let o = up(
        &[
            "--executor",
            "inprocess",
            "--scenario",
            sc.to_str().unwrap(),
            "--robots",
            "12",
            "--seed",
            "3",
            "--max-ticks",
            "160",
            "--chaos-at",
            "30:4",
        ],
        &out,
    );
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    out
}

#[test]
fn the_replay_page_draws_robots_where_the_recording_puts_them_and_the_scrubber_moves_them() {
    let _g = serial();
    chromium();
    let out = finished_run("view-replay");
    let (_, ticks) =
        swarm::recording::read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
            .unwrap();
    // Chunks of 10 ticks: the page holds only the chunks a picture needs.
    let v = ViewServer::start(&out, 10);
    let meta = json(&v.url, "/api/meta");
    assert_eq!(meta["live"], false);
    assert_eq!(meta["mission"], "search");
    let frames = json(&v.url, "/api/frames");
    let frames = frames.as_array().unwrap();
    assert_eq!(frames.len(), ticks.len());
    // The page's frames are the recording's numbers.
    for (f, t) in frames.iter().zip(&ticks) {
        assert_eq!(f["tick"].as_u64(), Some(t.tick));
        for (i, p) in t.poses.iter().enumerate() {
            assert_eq!(pose(f, i), [p[0], p[1]], "tick {} robot {i}", t.tick);
            assert_eq!(f["alive"][i].as_u64(), Some(t.alive[i] as u64));
        }
        // Search targets, found or not: one mark each, every tick.
        assert_eq!(f["layer"].as_array().unwrap().len(), 10, "tick {}", t.tick);
    }
    assert_eq!(frames[100]["alive"][4], 0, "robot 4 died at tick 30");
    let (k0, k1) = (40usize, 150usize);
    let a = screenshot(&format!("{}?tick={k0}&trail=0", v.url), 1200, 820, "a");
    let b = screenshot(&format!("{}?tick={k1}&trail=0", v.url), 1200, 820, "b");
    let ca = check_robots(&a, &meta, &frames[k0]);
    let cb = check_robots(&b, &meta, &frames[k1]);
    assert!(
        ca >= 4 && cb >= 4,
        "robots checked: {ca} at tick {k0}, {cb} at tick {k1}"
    );
    // The scrubber's tick moved the picture: the robots were elsewhere.
    let moved = (0..12)
        .filter(|&i| {
            let (p, q) = (
                project(&meta, pose(&frames[k0], i)),
                project(&meta, pose(&frames[k1], i)),
            );
            (p.0 - q.0).abs() + (p.1 - q.1).abs() > 10.0
        })
        .count();
    assert!(
        moved >= 6,
        "{moved} robots moved between ticks {k0} and {k1}"
    );
    assert!(a.differing_pixels(&b) > 200, "the two ticks look the same");
    // And the check sees it: tick k1's robots are not where tick k0's picture shows them.
    let (_, wrong) = compare_robots(&a, &meta, &frames[k1]);
    assert!(
        wrong.len() >= 3,
        "tick {k0}'s picture passes for tick {k1}: {wrong:?}"
    );
    // The page loaded only the chunk of tick k1 (no trail): 10 frames, nothing asked for.
    let n = ticks.len();
    let (_, run_js) = http("GET", &v.url, &format!("/run.js?tick={k1}&trail=0"));
    assert!(
        run_js.contains(&format!("\"count\": {n}, \"chunk\": 10, \"first\": {k1}, ")),
        "{}",
        &run_js[..run_js.len().min(300)]
    );
    let st = page_state(&format!("{}?tick={k1}&trail=0", v.url), 500, "chunk-a");
    assert_eq!(st["tick"], k1 as u64, "{st}");
    assert_eq!(st["frames_held"], (n.min(k1 + 10) - k1) as u64, "{st}");
    assert_eq!(st["requests"], 0, "{st}");
    // Played from tick 0 (run.js gives chunk 0 only): the page asks for each next chunk as
    // it goes and shows the tick it has reached. How far it gets depends on the machine:
    // the page's clock is virtual (10 s of it pass in about 1 s of real time) while the
    // fetches run in real time, so a page can end its budget with the next chunk still in
    // flight: 15 tries at load 3 reached ticks 35 to 159 of 160; two loaded CI runs on
    // 2026-12-04 ended at tick 9 with chunks 1-3 asked for and none back. A page that got no
    // further than chunk 0 is tried again (a fresh profile), up to PLAY_TRIES times; one whose
    // fetches never come back fails every try.
    const PLAY_TRIES: usize = 4;
    let url = format!("{}?tick=0&play=1&speed=1000&trail=5", v.url);
    let mut st = page_state(&url, 10_000, "chunk-play-1");
    for attempt in 2..=PLAY_TRIES {
        if st["cur"].as_u64().unwrap() >= 10 {
            break;
        }
        eprintln!("played page stopped in chunk 0 (try {}): {st}", attempt - 1);
        st = page_state(&url, 10_000, &format!("chunk-play-{attempt}"));
    }
    let cur = st["cur"].as_u64().unwrap();
    assert!(cur >= 10, "{st}");
    assert_eq!(st["tick"], cur, "{st}");
    assert!(st["requests"].as_u64().unwrap() >= cur / 10, "{st}");
    assert!(st["chunks_held"].as_u64().unwrap() <= 8, "{st}");
    assert!(st["frames_held"].as_u64().unwrap() <= 80, "{st}");
}

/// `up` of `args` in both executors with `--record-deliveries`: the two recordings.
fn up_both_with_deliveries(args: &[&str], tag: &str) -> (PathBuf, PathBuf) {
    let a = tmp_dir(&format!("{tag}-p"));
    let b = tmp_dir(&format!("{tag}-i"));
    for (dir, exec) in [(&a, "processes"), (&b, "inprocess")] {
        let mut all = args.to_vec();
        all.extend(["--record-deliveries", "--executor", exec]);
        let o = up(&all, dir);
        assert!(ended_by_itself(&o), "{exec}: {}", stderr(&o));
    }
    (a, b)
}

#[test]
fn the_page_shows_whom_the_selected_robot_heard_that_tick() {
    let _g = serial();
    chromium();
    let sc = configs().join("search.toml");
    let args = [
        "--scenario",
        sc.to_str().unwrap(),
        "--robots",
        "10",
        "--seed",
        "5",
        "--max-ticks",
        "60",
    ];
    let (p, i) = up_both_with_deliveries(&args, "view-heard");
    assert!(
        same_recording(&p, &i),
        "the executors recorded other deliveries"
    );
    // Off by default: the same run without the flag records version 6 and the same ticks.
    let plain = tmp_dir("view-heard-plain");
    let mut a = args.to_vec();
    a.extend(["--executor", "inprocess"]);
    assert!(ended_by_itself(&up(&a, &plain)));
    let read = |d: &Path| {
        swarm::recording::read_recording(std::fs::File::open(d.join("recording.bin")).unwrap())
            .unwrap()
    };
    let (h, ticks) = read(&i);
    let (h0, ticks0) = read(&plain);
    assert_eq!(h.version, swarm::recording::RECORDING_VERSION_DELIVERIES);
    assert_eq!(h0.version, swarm::recording::RECORDING_VERSION_BYTES);
    assert!(!std::fs::read_to_string(plain.join("scenario.toml"))
        .unwrap()
        .contains("record_deliveries"));
    assert_eq!(ticks.len(), ticks0.len());
    for (t, t0) in ticks.iter().zip(&ticks0) {
        assert_eq!(
            (&t.poses, &t.radio),
            (&t0.poses, &t0.radio),
            "tick {}",
            t.tick
        );
        assert!(t0.deliveries.is_none());
        // What the robots were handed is what the world counted delivered or malformed.
        let d = t.deliveries.as_ref().expect("deliveries every tick");
        let handed: u64 = d.heard.iter().map(|h| h.len() as u64).sum();
        assert_eq!(
            handed,
            t.radio.delivered + t.radio.malformed,
            "tick {}",
            t.tick
        );
    }
    // The robot and tick with the most senders.
    let senders = |t: &swarm::recording::TickRecord, r: usize| -> Vec<u32> {
        let mut s: Vec<u32> = t.deliveries.as_ref().unwrap().heard[r]
            .iter()
            .map(|m| m.sender)
            .collect();
        s.dedup();
        s
    };
    let (k, r) = (10..ticks.len())
        .flat_map(|k| (0..10).map(move |r| (k, r)))
        .max_by_key(|&(k, r)| (senders(&ticks[k], r).len(), std::cmp::Reverse((k, r))))
        .unwrap();
    let from = senders(&ticks[k], r);
    assert!(from.len() >= 2, "robot {r} heard from {from:?} at tick {k}");
    let heard = &ticks[k].deliveries.as_ref().unwrap().heard[r];
    let v = ViewServer::start(&i, 0);
    let meta = json(&v.url, "/api/meta");
    assert_eq!(meta["deliveries"], true);
    let f = json(&v.url, &format!("/api/frames?from={k}&to={}", k + 1));
    assert_eq!(
        f[0]["heard"][r],
        serde_json::json!(heard.iter().map(|m| m.sender).collect::<Vec<_>>())
    );
    let url = format!("{}?tick={k}&robot={r}&trail=0", v.url);
    let st = page_state(&url, 500, "heard");
    assert_eq!(st["heard"]["robot"], r as u64, "{st}");
    assert_eq!(st["heard"]["messages"], heard.len() as u64, "{st}");
    assert_eq!(
        st["heard"]["bytes"],
        heard.iter().map(|m| m.bytes as u64).sum::<u64>(),
        "{st}"
    );
    assert_eq!(st["heard"]["from"], serde_json::json!(from), "{st}");
    // The picture: a line from each sender to the robot, in the page's "heard" colour, seen
    // at the middle of each line clear of the robots; not there with no robot selected.
    let heard_rgb = [200u8, 0, 200];
    let frame = &f[0];
    let shot = screenshot(&url, 1200, 820, "heard");
    let none = screenshot(
        &format!("{}?tick={k}&trail=0", v.url),
        1200,
        820,
        "heard-none",
    );
    let to = project(&meta, pose(frame, r));
    let n = frame["poses"].as_array().unwrap().len();
    let (mut checked, mut seen, mut seen_without) = (0, 0, 0);
    for &j in &from {
        let s = project(&meta, pose(frame, j as usize));
        let mid = ((s.0 + to.0) / 2.0, (s.1 + to.1) / 2.0);
        let clear = (0..n).all(|q| {
            let c = project(&meta, pose(frame, q));
            ((c.0 - mid.0).powi(2) + (c.1 - mid.1).powi(2)).sqrt() > 12.0
        });
        if !clear {
            continue;
        }
        checked += 1;
        seen += near_colour(&shot, mid, heard_rgb) as usize;
        seen_without += near_colour(&none, mid, heard_rgb) as usize;
    }
    assert!(checked >= 1, "no line clear of the robots");
    assert_eq!(
        seen, checked,
        "lines from the senders seen: {seen} of {checked}"
    );
    assert_eq!(seen_without, 0, "heard lines with no robot selected");
    // The MCAP export has a fourth channel with the deliveries, one message a tick.
    let o = Command::new(orchestrator())
        .args(["export", i.to_str().unwrap(), "--format", "mcap"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(i.join("recording.mcap")).unwrap();
    let mut per_topic: std::collections::BTreeMap<String, usize> = Default::default();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/swarm/deliveries" && m.sequence as usize == k {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            let got = v["heard"]
                .as_array()
                .unwrap()
                .iter()
                .find(|h| h["receiver"] == r as u64)
                .expect("robot r in tick k's deliveries");
            assert_eq!(got["messages"], serde_json::to_value(heard).unwrap());
        }
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    assert_eq!(per_topic.get("/swarm/deliveries"), Some(&ticks.len()));
    assert_eq!(per_topic.len(), 4, "{per_topic:?}");
}

/// Whether a pixel within 1 px of `at` has colour `c` (within 40 a channel: lines are
/// anti-aliased).
fn near_colour(shot: &Shot, at: (f64, f64), c: [u8; 3]) -> bool {
    (-1..=1).any(|dx| {
        (-1..=1).any(|dy| {
            let got = shot.rgb(at.0 + dx as f64, at.1 + dy as f64);
            got.iter()
                .zip(c)
                .all(|(x, y)| (*x as i32 - y as i32).abs() <= 40)
        })
    })
}

/// The page's background at page point `p`: white, or inside the start region the region's
/// tint (rgba(120, 120, 255, 0.15) over white, page/viewer.js).
fn background(meta: &serde_json::Value, p: (f64, f64)) -> [f64; 3] {
    let r: Vec<f64> = (0..4)
        .map(|i| meta["start_region"][i].as_f64().unwrap())
        .collect();
    let (lo, hi) = (project(meta, [r[0], r[1]]), project(meta, [r[2], r[3]]));
    let inside = p.0 >= lo.0 && p.0 <= hi.0 && p.1 <= lo.1 && p.1 >= hi.1;
    if inside {
        [120.0, 120.0, 255.0].map(|c| 255.0 + 0.15 * (c - 255.0))
    } else {
        [255.0; 3]
    }
}

/// Whether a pixel within 1 px of `at` is a blend of `c` over the background `bg` at least
/// half `c` (a 1-px line drawn off the pixel grid is anti-aliased).
fn blend_of(shot: &Shot, at: (f64, f64), c: [u8; 3], bg: [f64; 3]) -> bool {
    (-1..=1).any(|dx| {
        (-1..=1).any(|dy| {
            let got = shot.rgb(at.0 + dx as f64, at.1 + dy as f64);
            // got = bg + a (c - bg) per channel: the share a of the mark's colour.
            let shares: Vec<f64> = (0..3)
                .filter(|&k| (c[k] as f64 - bg[k]).abs() > 40.0)
                .map(|k| (got[k] as f64 - bg[k]) / (c[k] as f64 - bg[k]))
                .collect();
            let (lo, hi) = shares
                .iter()
                .fold((2.0f64, 0.0f64), |(l, h), a| (l.min(*a), h.max(*a)));
            !shares.is_empty() && lo >= 0.5 && hi <= 1.1 && hi - lo < 0.25
        })
    })
}

/// A page point where a mark must show its colour, the colour, and whether it is filled there
/// (else a line through it).
type Sample = ((f64, f64), [u8; 3], bool);

/// The points where the picture of `mark` must show its colour, with that colour: a disc's
/// centre (filled), four points of a ring or a circle; none for triangles and paths (drawn
/// under the robots).
fn mark_samples(meta: &serde_json::Value, mark: &serde_json::Value) -> Vec<Sample> {
    let (kind, v) = mark.as_object().unwrap().iter().next().unwrap();
    let at = || {
        let a = &v["at"];
        project(meta, [a[0].as_f64().unwrap(), a[1].as_f64().unwrap()])
    };
    let col = |k: &str| [0, 1, 2].map(|i| v[k][i].as_u64().unwrap() as u8);
    let scale = (CANVAS_W - 2.0 * MARGIN) / meta["arena"][0].as_f64().unwrap();
    let around = |c: (f64, f64), r: f64| {
        [0.0f64, 90.0, 180.0, 270.0].map(|d| {
            (
                c.0 + r * d.to_radians().cos(),
                c.1 + r * d.to_radians().sin(),
            )
        })
    };
    match kind.as_str() {
        "Disc" => vec![(at(), col("fill"), true)],
        "Ring" => around(at(), v["px"].as_f64().unwrap())
            .into_iter()
            .map(|p| (p, col("colour"), false))
            .collect(),
        "Circle" => around(at(), (v["radius"].as_f64().unwrap() * scale).max(1.0))
            .into_iter()
            .map(|p| (p, col("colour"), false))
            .collect(),
        _ => vec![],
    }
}

/// Of the sample points of `marks` clear of every robot and of every other mark's samples
/// (`shift` px to the right of where they belong): (checked, showing their mark's colour).
fn check_marks(
    shot: &Shot,
    meta: &serde_json::Value,
    f: &serde_json::Value,
    shift: f64,
) -> (usize, usize) {
    let n = f["poses"].as_array().unwrap().len();
    let robots: Vec<(f64, f64)> = (0..n).map(|i| project(meta, pose(f, i))).collect();
    let marks = f["layer"].as_array().unwrap();
    let scale = (CANVAS_W - 2.0 * MARGIN) / meta["arena"][0].as_f64().unwrap();
    // Disc obstacles, drawn under the marks: (page centre, page radius).
    let discs: Vec<((f64, f64), f64)> = meta["discs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| {
            let c = [d[0][0].as_f64().unwrap(), d[0][1].as_f64().unwrap()];
            (project(meta, c), d[1].as_f64().unwrap() * scale)
        })
        .collect();
    let all: Vec<Vec<Sample>> = marks.iter().map(|m| mark_samples(meta, m)).collect();
    let (mut checked, mut ok) = (0, 0);
    for (mi, samples) in all.iter().enumerate() {
        for &(p, c, filled) in samples {
            let d = |q: (f64, f64)| ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).sqrt();
            let clear = robots.iter().all(|&q| d(q) > 12.0)
                && discs.iter().all(|&(q, r)| d(q) > r + 3.0)
                && all
                    .iter()
                    .enumerate()
                    .filter(|(mj, _)| *mj != mi)
                    .all(|(_, o)| o.iter().all(|s| d(s.0) > 6.0))
                && p.0 > 2.0
                && p.1 > 2.0
                && p.0 < CANVAS_W - 2.0
                && p.1 < shot.height as f64 - 2.0;
            if !clear {
                continue;
            }
            let q = (p.0 + shift, p.1);
            checked += 1;
            let hit = if filled {
                close(shot.rgb(q.0, q.1), c)
            } else {
                blend_of(shot, q, c, background(meta, q))
            };
            ok += hit as usize;
        }
    }
    (checked, ok)
}

/// Counts of the recording's marks by kind at frame `f`, as the page counts what it drew.
fn mark_counts(f: &serde_json::Value) -> serde_json::Value {
    let mut m = serde_json::Map::new();
    for mark in f["layer"].as_array().unwrap() {
        let (kind, v) = mark.as_object().unwrap().iter().next().unwrap();
        if kind == "Path" && v["points"].as_array().unwrap().is_empty() {
            continue;
        }
        let e = m.entry(kind.clone()).or_insert(serde_json::json!(0));
        *e = serde_json::json!(e.as_u64().unwrap() + 1);
    }
    serde_json::Value::Object(m)
}

/// A short in-process run of `config` (`ticks` ticks); the page at its last tick draws every
/// mark of the mission's layer there, the marks' colours where they belong.
fn layer_is_drawn(config: &str, ticks: &str, tag: &str, kinds: &[&str]) {
    let out = tmp_dir(tag);
    let sc = configs().join(config);
    let o = up(
        &[
            "--executor",
            "inprocess",
            "--scenario",
            sc.to_str().unwrap(),
            "--max-ticks",
            ticks,
        ],
        &out,
    );
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    let v = ViewServer::start(&out, 0);
    let meta = json(&v.url, "/api/meta");
    let frames = json(&v.url, "/api/frames");
    let frames = frames.as_array().unwrap();
    let k = frames.len() - 1;
    let f = &frames[k];
    let want = mark_counts(f);
    for kind in kinds {
        assert!(want[kind].as_u64().unwrap_or(0) > 0, "no {kind} in {want}");
    }
    let url = format!("{}?tick={k}&trail=0", v.url);
    let st = page_state(&url, 500, tag);
    assert_eq!(
        st["marks"], want,
        "the page drew other marks than the recording's"
    );
    let shot = screenshot(&url, 1200, 820, tag);
    let (checked, ok) = check_marks(&shot, &meta, f, 0.0);
    assert!(checked >= 3, "{tag}: {checked} mark points clear to check");
    assert!(
        ok * 10 >= checked * 9,
        "{tag}: {ok} of {checked} mark points show their colour"
    );
    // And the check sees a picture without them: the same points 15 px to the right fail.
    let (c2, ok2) = check_marks(&shot, &meta, f, 15.0);
    assert!(ok2 * 2 < c2, "{tag}: shifted marks pass: {ok2} of {c2}");
}

#[test]
fn the_formation_layer_is_drawn_slots_and_discs() {
    let _g = serial();
    chromium();
    layer_is_drawn("formation.toml", "30", "view-formation", &["Circle"]);
}

#[test]
fn the_hunt_layer_is_drawn_evaders_ranges_and_robots() {
    let _g = serial();
    chromium();
    layer_is_drawn(
        "hunt-auction.toml",
        "40",
        "view-hunt",
        &["Circle", "Triangle", "Path"],
    );
}

#[test]
fn the_live_page_shows_the_running_run_and_its_kill_button_makes_a_fault() {
    let _g = serial();
    chromium();
    let out = tmp_dir("view-live");
    let id = own_run_id("view-live");
    let mut child = spawn_up_as(
        &[
            "--view",
            "--scenario",
            roam(),
            "--robots",
            "6",
            // 15 s: the page is still served when a slow Chromium takes its screenshot.
            "--max-ticks",
            "450",
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
    while json(&url, "/api/frames").as_array().unwrap().len() < 20 {
        assert!(t.elapsed() < Duration::from_secs(60), "no frames");
        std::thread::sleep(Duration::from_millis(50));
    }
    let meta = json(&url, "/api/meta");
    assert_eq!(meta["live"], true);
    // The stream: frames in tick order from the one asked for; then the page goes away.
    {
        let addr = url.trim_start_matches("http://").trim_end_matches('/');
        let mut s = TcpStream::connect(addr).unwrap();
        write!(s, "GET /api/stream?from=5 HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
        let mut r = BufReader::new(s);
        let mut ticks = Vec::new();
        let mut line = String::new();
        while ticks.len() < 25 {
            line.clear();
            assert!(r.read_line(&mut line).unwrap() > 0, "stream ended early");
            if let Some(d) = line.strip_prefix("data: ") {
                let f: serde_json::Value = serde_json::from_str(d).unwrap();
                ticks.push(f["tick"].as_u64().unwrap());
            }
        }
        assert_eq!(ticks, (5..30).collect::<Vec<u64>>());
        // Dropped here mid-stream: the run must not notice.
    }
    let (status, body) = http("POST", &url, "/api/kill?robot=2");
    assert_eq!(status, 200, "{body}");
    assert!(body.contains("killed robot 2"), "{body}");
    // The frame where robot 2 is dead, then a picture of it.
    let t = Instant::now();
    let dead_at = loop {
        let frames = json(&url, "/api/frames");
        if let Some(f) = frames
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["alive"][2] == 0)
        {
            break f["tick"].as_u64().unwrap() as usize;
        }
        assert!(t.elapsed() < Duration::from_secs(20), "robot 2 never died");
        std::thread::sleep(Duration::from_millis(50));
    };
    let k = dead_at + 2;
    while json(&url, "/api/frames").as_array().unwrap().len() <= k {
        std::thread::sleep(Duration::from_millis(20));
    }
    let frames = json(&url, "/api/frames");
    let shot = screenshot(&format!("{url}?tick={k}&trail=0"), 1200, 820, "live");
    let checked = check_robots(&shot, &meta, &frames[k]);
    assert!(checked >= 3, "robots checked: {checked}");
    let o = child.wait_with_output().unwrap();
    assert!(
        ended_by_itself(&o),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["end"], "completed", "{s}");
    assert_eq!(s["ticks"], 450);
    let faults = s["faults"].as_array().unwrap();
    assert_eq!(faults.len(), 1, "{s}");
    assert_eq!(faults[0]["robot"], 2);
    // The fault's tick is the barrier's when the orchestrator reaped the agent: the tick the
    // recording first shows it dead, or the one before.
    let tick = faults[0]["tick"].as_u64().unwrap();
    assert!(
        tick + 1 == dead_at as u64 || tick == dead_at as u64,
        "fault at tick {tick}, first dead frame {dead_at}"
    );
    assert!(
        faults[0]["cause"]
            .as_str()
            .unwrap()
            .contains("process died"),
        "{s}"
    );
    assert_left_nothing(&out);
}

#[test]
fn the_csv_holds_the_recordings_numbers_and_the_mcap_reads_back_whole() {
    let _g = serial();
    let out = finished_run("view-export");
    let (_, ticks) =
        swarm::recording::read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
            .unwrap();
    for fmt in ["csv", "mcap"] {
        let o = Command::new(orchestrator())
            .args(["export", out.to_str().unwrap(), "--format", fmt])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let csv = std::fs::read_to_string(out.join("recording.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("tick,robot,x,y,heading,state,alive"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), ticks.len() * 12);
    for (row, (t, i)) in rows
        .iter()
        .zip(ticks.iter().flat_map(|t| (0..12).map(move |i| (t, i))))
    {
        let c: Vec<&str> = row.split(',').collect();
        assert_eq!(c[0].parse::<u64>().unwrap(), t.tick);
        assert_eq!(c[1].parse::<usize>().unwrap(), i);
        let xyh: Vec<f64> = c[2..5].iter().map(|v| v.parse().unwrap()).collect();
        assert_eq!(xyh, t.poses[i].to_vec(), "tick {} robot {i}", t.tick);
        assert_eq!(c[5].parse::<u8>().unwrap(), t.states[i]);
        assert_eq!(c[6].parse::<u8>().unwrap(), t.alive[i]);
    }
    let bytes = std::fs::read(out.join("recording.mcap")).unwrap();
    let mut per_topic: std::collections::BTreeMap<String, usize> = Default::default();
    let mut first_pose: Option<serde_json::Value> = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.encoding, "jsonschema");
        if m.channel.topic == "/swarm/poses" && first_pose.is_none() {
            first_pose = Some(serde_json::from_slice(&m.data).unwrap());
        }
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    let n = ticks.len();
    assert_eq!(
        per_topic.into_iter().collect::<Vec<_>>(),
        vec![
            ("/swarm/entities".to_string(), n),
            ("/swarm/poses".to_string(), n),
            ("/swarm/radio".to_string(), n)
        ]
    );
    let p = first_pose.unwrap();
    assert_eq!(p["robots"][7]["x"].as_f64(), Some(ticks[0].poses[7][0]));
    assert_eq!(
        p["robots"][7]["heading"].as_f64(),
        Some(ticks[0].poses[7][2])
    );
}
