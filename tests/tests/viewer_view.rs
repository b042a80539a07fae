//! The viewer's picture in a real headless Chromium driven by real mouse input over the
//! DevTools pipe (issue 39): the canvas fits a 1280x720 window with the whole arena, the
//! wheel zooms at the pointer, a drag pans, "fit arena" brings the whole arena back; a
//! formation run's counter is the mission's own figure; the legends list only what the run
//! has, in distinct colours, and a live run does not call unfound targets missed.
//!
//! Set `SWARM_VIEWER_SHOTS=DIR` to keep the screenshots (to look at them).

mod browser;

use browser::cdp::Browser;
use browser::*;
use e2e::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The window of the complaint.
const W: u32 = 1280;
const H: u32 = 720;

/// Keeps `png` as `name`.png in $SWARM_VIEWER_SHOTS, when set.
fn keep_shot(png: &[u8], name: &str) {
    if let Some(dir) = std::env::var_os("SWARM_VIEWER_SHOTS") {
        let dir = PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(format!("{name}.png")), png).unwrap();
    }
}

/// The page's screenshot, kept as `name` (see [`keep_shot`]).
fn shot(b: &mut Browser, name: &str) -> Shot {
    let png = b.screenshot_png();
    keep_shot(&png, name);
    Shot::decode(&png)
}

/// The page's view as its `#state` gives it, in the test window.
fn view_of(st: &serde_json::Value) -> View {
    let v = &st["view"];
    View {
        window: (W, H),
        zoom: v["zoom"].as_f64().unwrap(),
        centre: Some([v["cx"].as_f64().unwrap(), v["cy"].as_f64().unwrap()]),
    }
}

/// An in-process run of `config` with `extra` arguments; its folder.
fn run(config: &str, extra: &[&str], tag: &str) -> PathBuf {
    let out = tmp_dir(tag);
    let sc = configs().join(config);
    let mut args = vec![
        "--executor",
        "inprocess",
        "--scenario",
        sc.to_str().unwrap(),
    ];
    args.extend(extra);
    let o = up(&args, &out);
    assert!(ended_by_itself(&o), "{}", stderr(&o));
    out
}

/// Whether the 3 x 3 pixels around `at` hold a pixel within 40 a channel of `c`.
fn shows(shot: &Shot, at: (f64, f64), c: [u8; 3]) -> bool {
    near_colour(shot, at, c)
}

/// The robot clear of the others (by `clear` px) nearest the canvas's centre, and its page
/// point in view `v`.
fn clear_robot(meta: &serde_json::Value, f: &serde_json::Value, v: View) -> (usize, (f64, f64)) {
    let n = f["poses"].as_array().unwrap().len();
    let at: Vec<(f64, f64)> = (0..n).map(|i| v.project(meta, pose(f, i))).collect();
    let (cw, ch) = v.canvas();
    (0..n)
        .filter(|&i| f["alive"][i] == 1)
        .filter(|&i| {
            (0..n).all(|j| {
                j == i || ((at[i].0 - at[j].0).powi(2) + (at[i].1 - at[j].1).powi(2)).sqrt() > 40.0
            })
        })
        .map(|i| (i, at[i]))
        .min_by(|a, b| {
            let d = |p: (f64, f64)| (p.0 - cw / 2.0).powi(2) + (p.1 - ch / 2.0).powi(2);
            d(a.1).total_cmp(&d(b.1))
        })
        .expect("a robot clear of the others")
}

#[test]
fn the_page_fits_a_1280x720_window_and_zooms_at_the_wheel_pans_by_dragging_and_fits_again() {
    let _g = serial();
    chromium();
    let out = run(
        "search.toml",
        &["--robots", "12", "--seed", "3", "--max-ticks", "120"],
        "view-zoom",
    );
    let v = ViewServer::start(&out, 0);
    let meta = json(&v.url, "/api/meta");
    let k = 100;
    let frames = json(&v.url, &format!("/api/frames?from={k}&to={}", k + 1));
    let f = &frames[0];
    let mut b = Browser::open(&format!("{}?tick={k}&trail=0", v.url), W, H, "zoom");
    let st = b.state();
    assert_eq!(st["tick"], k, "{st}");
    // The canvas fills the window left of the side panel; the whole arena is in it: each of
    // its four sides' middles shows the arena's black border.
    let fit = View::fit(W, H);
    assert_eq!(
        (st["view"]["width"].as_f64(), st["view"]["height"].as_f64()),
        (Some(fit.canvas().0), Some(fit.canvas().1)),
        "{st}"
    );
    assert_eq!(st["view"]["zoom"], 1.0);
    let whole = shot(&mut b, "fit-1280x720");
    let (aw, ah) = arena(&meta);
    for (name, p) in [
        ("bottom", [aw / 2.0, 0.0]),
        ("top", [aw / 2.0, ah]),
        ("left", [0.0, ah / 2.0]),
        ("right", [aw, ah / 2.0]),
    ] {
        let at = fit.project(&meta, p);
        assert!(
            at.0 >= 0.0 && at.1 >= 0.0 && at.0 < fit.canvas().0 && at.1 < H as f64,
            "the arena's {name} side is off the canvas at {at:?}"
        );
        assert!(
            shows(&whole, at, [0, 0, 0]),
            "no border at the {name} side {at:?}"
        );
    }
    assert!(check_robots_in(&whole, &meta, f, fit) >= 4);

    // The wheel zooms in about the pointer (on a whole pixel: mouse events carry whole
    // pixels): the robot under it stays under it, the others move away from it.
    let (i, r) = clear_robot(&meta, f, fit);
    let p = (r.0.round(), r.1.round());
    b.wheel(p.0, p.1, -300.0);
    let st = b.state();
    let zoomed = view_of(&st);
    let want = (300.0 * 0.002f64).exp();
    assert!(
        (zoomed.zoom - want).abs() < 1e-9,
        "zoom {} want {want}",
        zoomed.zoom
    );
    let q = zoomed.project(&meta, pose(f, i));
    let want_q = (p.0 + (r.0 - p.0) * want, p.1 + (r.1 - p.1) * want);
    assert!(
        (q.0 - want_q.0).abs() < 1e-6 && (q.1 - want_q.1).abs() < 1e-6 && (q.0 - p.0).abs() < 1.0,
        "robot {i} at {r:?} went to {q:?}, not {want_q:?}, under the pointer at {p:?}"
    );
    let zshot = shot(&mut b, "wheel-zoomed");
    assert!(check_robots_in(&zshot, &meta, f, zoomed) >= 2);
    assert!(shows(&zshot, q, robot_colour(&meta, f, i)));
    // The same picture as the page's URL view gives (?zoom=&cx=&cy=), for a plain screenshot.
    let c = zoomed.centre.unwrap();
    let url = format!(
        "{}?tick={k}&trail=0&zoom={}&cx={}&cy={}",
        v.url, zoomed.zoom, c[0], c[1]
    );
    let plain = screenshot(&url, W, H, "zoom-url");
    assert!(check_robots_in(&plain, &meta, f, zoomed) >= 2);

    // A drag pans: every robot moves with the pointer, and nothing is selected.
    b.drag(p, (p.0 + 120.0, p.1 + 80.0), 6);
    let st = b.state();
    let panned = view_of(&st);
    assert_eq!(
        st["selected"],
        serde_json::Value::Null,
        "a drag selected a robot"
    );
    let s = zoomed.scale(&meta);
    let (c0, c1) = (zoomed.centre.unwrap(), panned.centre.unwrap());
    assert!(
        (c1[0] - (c0[0] - 120.0 / s)).abs() < 1e-6 && (c1[1] - (c0[1] + 80.0 / s)).abs() < 1e-6,
        "centre {c0:?} -> {c1:?}"
    );
    let pshot = shot(&mut b, "dragged");
    assert!(check_robots_in(&pshot, &meta, f, panned) >= 2);
    assert!(shows(
        &pshot,
        (q.0 + 120.0, q.1 + 80.0),
        robot_colour(&meta, f, i)
    ));
    // A click (no drag) on the robot selects it.
    b.click(p.0 + 120.0, p.1 + 80.0);
    assert_eq!(b.state()["selected"], i);

    // "fit arena" brings the whole arena back: the first picture but for the selection.
    b.click_on("#fit");
    let st = b.state();
    assert_eq!(st["view"]["zoom"], 1.0, "{st}");
    assert_eq!(
        (st["view"]["cx"].as_f64(), st["view"]["cy"].as_f64()),
        (Some(aw / 2.0), Some(ah / 2.0))
    );
    b.eval("document.getElementById('zoomout').click()");
    b.click_on("#fit");
    let again = shot(&mut b, "fit-again");
    assert!(check_robots_in(&again, &meta, f, fit) >= 4);
    for p in [[aw / 2.0, 0.0], [aw / 2.0, ah]] {
        assert!(shows(&again, fit.project(&meta, p), [0, 0, 0]));
    }
}

#[test]
fn a_formation_runs_counter_is_the_missions_robots_in_place() {
    let _g = serial();
    chromium();
    let out = run(
        "formation.toml",
        &["--max-ticks", "300"],
        "view-form-counter",
    );
    let s = summary(&out);
    let in_place = s["mission"]["formation"]["robots_in_place"]
        .as_u64()
        .unwrap();
    assert!(in_place > 0, "{s}");
    let v = ViewServer::start(&out, 0);
    let meta = json(&v.url, "/api/meta");
    let frames = json(&v.url, "/api/frames");
    let frames = frames.as_array().unwrap();
    let last = frames.len() - 1;
    // Every frame's figure is the last Progress event's so far; the last is the summary's.
    let (_, ticks) =
        swarm::recording::read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
            .unwrap();
    let mut now = (0, meta["progress_total"].as_u64().unwrap() as u32);
    let mut changes = 0;
    for (t, f) in ticks.iter().zip(frames) {
        for e in &t.events {
            if let swarm::recording::Event::Progress { done, total } = e {
                now = (*done, *total);
                changes += 1;
            }
        }
        assert_eq!(
            (f["done"].as_u64(), f["total"].as_u64()),
            (Some(now.0 as u64), Some(now.1 as u64)),
            "tick {}",
            t.tick
        );
    }
    assert!(changes >= 2, "{changes} progress changes");
    assert_eq!(now.0 as u64, in_place);
    let mut b = Browser::open(&format!("{}?tick={last}&trail=0", v.url), W, H, "counter");
    let st = b.state();
    assert_eq!(
        st["progress"],
        serde_json::json!({"label": "robots in place", "done": in_place, "total": now.1}),
        "{st}"
    );
    let info = b.eval("document.getElementById('info').textContent");
    assert!(
        info.as_str()
            .unwrap()
            .contains(&format!("robots in place {in_place}/{}", now.1)),
        "{info}"
    );
    shot(&mut b, "formation-counter");
}

/// Checks the page's legend rows: each swatch shows its colour in the screenshot, and no two
/// rows share a colour (a robot's tint, a mark's, the obstacles'; robot triangles, coloured
/// by task, aside); returns the labels.
fn check_legend(st: &serde_json::Value, shot: &Shot) -> Vec<String> {
    let rows = st["legend"].as_array().unwrap();
    let mut colours = std::collections::BTreeMap::new();
    for r in rows {
        let c = [0, 1, 2].map(|k| r["colour"][k].as_u64().unwrap() as u8);
        let at = (r["at"][0].as_f64().unwrap(), r["at"][1].as_f64().unwrap());
        assert!(shows(shot, at, c), "legend {r}: not its colour at {at:?}");
        // Robots drawn as triangles take their task's colour: the swatch shows one of them.
        if r["kind"] == "Triangle" {
            continue;
        }
        if let Some(other) = colours.insert(c, r["label"].clone()) {
            panic!(
                "legend rows {other} and {} share colour {c:?}: {st}",
                r["label"]
            );
        }
    }
    rows.iter()
        .map(|r| r["label"].as_str().unwrap().to_string())
        .collect()
}

/// A live page's state and a screenshot of the same picture: frames keep arriving, and a
/// legend row that appears between the two moves the rows below it, so the pair is taken
/// again until the legend reads the same before and after the screenshot.
fn steady_shot(b: &mut Browser, name: &str) -> (serde_json::Value, Shot) {
    for _ in 0..50 {
        let before = b.state();
        let s = shot(b, name);
        let after = b.state();
        if before["legend"] == after["legend"] {
            return (after, s);
        }
    }
    panic!("the live page's legend never held still over a screenshot");
}

/// The display states' names the recording's robots were in.
fn states_in(out: &Path, meta: &serde_json::Value) -> Vec<String> {
    let (_, ticks) =
        swarm::recording::read_recording(std::fs::File::open(out.join("recording.bin")).unwrap())
            .unwrap();
    let seen: std::collections::BTreeSet<u8> = ticks
        .iter()
        .flat_map(|t| t.states.iter().copied())
        .collect();
    meta["states"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| seen.contains(&(d["state"].as_u64().unwrap() as u8)))
        .map(|d| d["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn legends_list_only_what_the_run_has_in_distinct_colours() {
    let _g = serial();
    chromium();
    // Hunt, 3 evaders: no T4..T8; the robots' tasks are those the recording has.
    let out = run(
        "hunt-auction.toml",
        &["--max-ticks", "40"],
        "view-legend-hunt",
    );
    let v = ViewServer::start(&out, 0);
    let meta = json(&v.url, "/api/meta");
    let mut b = Browser::open(&format!("{}?tick=39&trail=0", v.url), W, H, "legend-hunt");
    let st = b.state();
    let labels = check_legend(&st, &shot(&mut b, "legend-hunt"));
    let states = states_in(&out, &meta);
    for name in meta["states"].as_array().unwrap() {
        let name = name["name"].as_str().unwrap();
        assert_eq!(
            labels.iter().any(|l| l == name),
            states.iter().any(|s| s == name),
            "state {name}: legend {labels:?}, recording {states:?}"
        );
    }
    for k in 4..=8 {
        assert!(!labels.contains(&format!("T{k}")), "{labels:?}");
    }
    assert!(!labels.iter().any(|l| l == "start region"), "{labels:?}");
    // Captured and free evaders differ in colour, not only in shape.
    let legend = meta["legend"].as_array().unwrap();
    let colour = |label: &str| {
        let e = legend.iter().find(|e| e["label"] == label).unwrap();
        let v = e["mark"].as_object().unwrap().values().next().unwrap();
        v.get("fill").unwrap_or(&v["colour"]).clone()
    };
    assert_ne!(
        colour("evader captured"),
        colour("evader free (circles: r_e, r_s)")
    );
    drop(b);
    drop(v);

    // Formation: obstacles and final discs in distinct colours, both listed; no start-region
    // tint (the robots start anywhere in the arena).
    let out = run(
        "formation.toml",
        &["--max-ticks", "300"],
        "view-legend-form",
    );
    let v = ViewServer::start(&out, 0);
    let meta = json(&v.url, "/api/meta");
    assert_eq!(meta["start_region_shown"], false);
    let frames = json(&v.url, "/api/frames");
    let last = frames.as_array().unwrap().len() - 1;
    let mut b = Browser::open(
        &format!("{}?tick={last}&trail=0", v.url),
        W,
        H,
        "legend-form",
    );
    let st = b.state();
    let form = shot(&mut b, "legend-formation");
    let labels = check_legend(&st, &form);
    let row = |label: &str| {
        st["legend"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["label"] == label)
            .unwrap_or_else(|| panic!("no {label:?} in {st}"))["colour"]
            .clone()
    };
    assert_ne!(row("obstacle"), row("final discs (small: lost robot)"));
    assert!(!labels.iter().any(|l| l == "start region"), "{labels:?}");
    // An obstacle's centre shows the obstacle colour; the arena's corner is white, untinted.
    let fit = View::fit(W, H);
    let d = &meta["discs"][0][0];
    let centre = fit.project(&meta, [d[0].as_f64().unwrap(), d[1].as_f64().unwrap()]);
    let oc = row("obstacle");
    let oc = [0, 1, 2].map(|k| oc[k].as_u64().unwrap() as u8);
    assert!(
        close(form.rgb(centre.0, centre.1), oc),
        "obstacle at {centre:?}"
    );
    let corner = fit.project(&meta, [0.3, 0.3]);
    assert_eq!(form.rgb(corner.0 + 3.0, corner.1 - 3.0), [255, 255, 255]);
    drop(b);
    drop(v);

    // A live search: unfound targets are "not found yet" while it runs, "missed" after.
    let out = tmp_dir("view-legend-live");
    let sc = configs().join("search.toml");
    let mut child = spawn_up_as(
        &[
            "--view",
            "--executor",
            "inprocess",
            "--scenario",
            sc.to_str().unwrap(),
            "--robots",
            "6",
            "--seed",
            "4",
            "--max-ticks",
            "150",
            "--tick-hz",
            "25",
        ],
        &out,
        None,
    );
    let url = viewer_url(&mut child);
    let t = Instant::now();
    while json(&url, "/api/frames").as_array().unwrap().len() < 5 {
        assert!(t.elapsed() < Duration::from_secs(60), "no frames");
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut b = Browser::open(&url, W, H, "legend-live");
    let (running, running_shot) = steady_shot(&mut b, "legend-live-running");
    let live = check_legend(&running, &running_shot);
    assert!(live.iter().any(|l| l == "target not found yet"), "{live:?}");
    assert!(!live.iter().any(|l| l.contains("missed")), "{live:?}");
    b.wait_for("document.getElementById('status').textContent.startsWith('live run: ended')");
    let o = child.wait_with_output().unwrap();
    assert!(
        ended_by_itself(&o),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let ended = b.state();
    let after = check_legend(&ended, &shot(&mut b, "legend-live-ended"));
    let s = summary(&out);
    let found = s["mission"]["search"]["found"].as_u64();
    let targets = s["mission"]["search"]["targets"].as_u64();
    if found < targets {
        assert!(after.iter().any(|l| l == "target missed"), "{after:?} {s}");
    }
    assert!(
        !after.iter().any(|l| l == "target not found yet"),
        "{after:?}"
    );
}
