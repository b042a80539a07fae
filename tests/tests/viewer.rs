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

/// A screenshot of `url` (window `w` x `h`), decoded: (width, RGB rows).
fn screenshot(url: &str, w: u32, h: u32, tag: &str) -> Shot {
    let dir = tmp_dir(&format!("chromium-{tag}"));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("shot.png");
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
        .arg(format!("--screenshot={}", file.display()))
        .arg(format!("--window-size={w},{h}"))
        .arg(url)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromium");
    let t = Instant::now();
    while c.try_wait().unwrap().is_none() {
        if t.elapsed() > Duration::from_secs(90) {
            let _ = c.kill();
            let _ = c.wait();
            panic!("chromium took over 90 s for {url}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let bytes = std::fs::read(&file).unwrap_or_else(|e| panic!("no screenshot of {url}: {e}"));
    let _ = std::fs::remove_dir_all(&dir);
    Shot::decode(&bytes)
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
    fn start(dir: &Path) -> ViewServer {
        let mut child = Command::new(orchestrator())
            .arg("view")
            .arg(dir)
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
    assert!(o.status.success(), "{}", stderr(&o));
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
    let v = ViewServer::start(&out);
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
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
