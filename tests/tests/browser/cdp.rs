//! A real headless Chromium driven over the DevTools protocol on a pipe
//! (`--remote-debugging-pipe`: commands on fd 3, answers on fd 4, JSON messages ended by a
//! NUL byte): real mouse events (wheel, drag, clicks), the page's JavaScript evaluated, PNG
//! screenshots. No WebSocket and no driver crate: a pipe and serde_json.

use base64::Engine;
use std::io::{BufRead, BufReader, Write};
use std::os::fd::{FromRawFd, OwnedFd};
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

/// How long one DevTools command may take (page loads included): a loaded machine's
/// Chromium answers in well under a second.
pub const CDP_LIMIT: Duration = Duration::from_secs(60);

/// One Chromium with one page.
pub struct Browser {
    child: Child,
    to: std::fs::File,
    from: Receiver<serde_json::Value>,
    next: u64,
    session: String,
    dir: PathBuf,
}

/// A pipe whose two ends close on exec (the child gets its ends by dup2, which clears it).
fn pipe() -> (OwnedFd, OwnedFd) {
    let mut fds = [0i32; 2];
    // SAFETY: pipe2 fills two new descriptors, owned from here on.
    let rc = unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) };
    assert_eq!(rc, 0, "pipe2");
    // SAFETY: both are new, open and ours.
    unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) }
}

impl Browser {
    /// Chromium with a `w` x `h` viewer page at `url`, once the page has loaded and drawn
    /// (its `#state` holds JSON).
    pub fn open(url: &str, w: u32, h: u32, tag: &str) -> Browser {
        Browser::open_page(
            url,
            w,
            h,
            tag,
            "!!document.getElementById('state') && \
             document.getElementById('state').textContent.length > 0",
        )
    }

    /// Chromium with a `w` x `h` page at `url`, once it has loaded and JavaScript `ready` is
    /// true in it.
    pub fn open_page(url: &str, w: u32, h: u32, tag: &str, ready: &str) -> Browser {
        use std::os::fd::AsRawFd;
        let dir = e2e::tmp_dir(&format!("cdp-{tag}"));
        std::fs::create_dir_all(&dir).unwrap();
        let (cmd_r, cmd_w) = pipe();
        let (ans_r, ans_w) = pipe();
        let (r, w_fd) = (cmd_r.as_raw_fd(), ans_w.as_raw_fd());
        let mut c = Command::new(super::chromium());
        c.args(super::CHROMIUM_ARGS)
            .arg("--remote-debugging-pipe")
            .arg(format!("--user-data-dir={}", dir.join("profile").display()))
            .arg(format!("--window-size={w},{h}"))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        // SAFETY: only async-signal-safe calls (dup2) between fork and exec.
        unsafe {
            c.pre_exec(move || {
                if libc::dup2(r, 3) < 0 || libc::dup2(w_fd, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = c.spawn().expect("start chromium");
        drop((cmd_r, ans_w));
        let (tx, from) = channel();
        let mut rd = BufReader::new(std::fs::File::from(ans_r));
        std::thread::spawn(move || loop {
            let mut msg = Vec::new();
            match rd.read_until(0, &mut msg) {
                Ok(0) | Err(_) => return,
                Ok(_) => {
                    msg.pop();
                    if let Ok(v) = serde_json::from_slice(&msg) {
                        if tx.send(v).is_err() {
                            return;
                        }
                    }
                }
            }
        });
        let mut b = Browser {
            child,
            to: std::fs::File::from(cmd_w),
            from,
            next: 0,
            session: String::new(),
            dir,
        };
        let target = b.call(
            "Target.createTarget",
            serde_json::json!({"url": "about:blank"}),
        );
        let id = target["targetId"].as_str().unwrap().to_string();
        let s = b.call(
            "Target.attachToTarget",
            serde_json::json!({"targetId": id, "flatten": true}),
        );
        b.session = s["sessionId"].as_str().unwrap().to_string();
        b.call(
            "Emulation.setDeviceMetricsOverride",
            serde_json::json!({"width": w, "height": h, "deviceScaleFactor": 1, "mobile": false}),
        );
        b.call("Page.navigate", serde_json::json!({"url": url}));
        b.wait_for(&format!("document.readyState === 'complete' && ({ready})"));
        b
    }

    /// Sends `method` (to the page's session once attached) and waits for its answer.
    pub fn call(&mut self, method: &str, params: serde_json::Value) -> serde_json::Value {
        self.next += 1;
        let id = self.next;
        let mut msg = serde_json::json!({"id": id, "method": method, "params": params});
        if !self.session.is_empty() {
            msg["sessionId"] = self.session.clone().into();
        }
        let mut bytes = serde_json::to_vec(&msg).unwrap();
        bytes.push(0);
        self.to.write_all(&bytes).expect("write to chromium");
        let t = Instant::now();
        loop {
            let left = CDP_LIMIT.saturating_sub(t.elapsed());
            let v = self
                .from
                .recv_timeout(left)
                .unwrap_or_else(|e| panic!("chromium did not answer {method}: {e}"));
            if v["id"].as_u64() == Some(id) {
                if let Some(err) = v.get("error") {
                    panic!("{method}: {err}");
                }
                return v["result"].clone();
            }
        }
    }

    /// The value of JavaScript `expr` in the page (promises awaited).
    pub fn eval(&mut self, expr: &str) -> serde_json::Value {
        let r = self.call(
            "Runtime.evaluate",
            serde_json::json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("{expr}: {e}");
        }
        r["result"]["value"].clone()
    }

    /// Waits until JavaScript `cond` is true in the page (at most [`CDP_LIMIT`]).
    pub fn wait_for(&mut self, cond: &str) {
        let t = Instant::now();
        while self.eval(cond) != serde_json::Value::Bool(true) {
            assert!(t.elapsed() < CDP_LIMIT, "never true: {cond}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// The page's `#state` (JSON: tick shown, view, legend, progress, ...), after the page
    /// has drawn what it was last asked to (two animation frames).
    pub fn state(&mut self) -> serde_json::Value {
        let s = self.eval(
            "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => \
             r(document.getElementById('state').textContent))))",
        );
        serde_json::from_str(s.as_str().unwrap()).unwrap()
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64, extra: serde_json::Value) {
        let mut p = serde_json::json!({"type": kind, "x": x, "y": y});
        p.as_object_mut()
            .unwrap()
            .extend(extra.as_object().unwrap().clone());
        self.call("Input.dispatchMouseEvent", p);
    }

    /// A turn of the mouse wheel at (x, y): `dy` < 0 scrolls up (zooms in).
    pub fn wheel(&mut self, x: f64, y: f64, dy: f64) {
        self.mouse(
            "mouseWheel",
            x,
            y,
            serde_json::json!({"deltaX": 0, "deltaY": dy}),
        );
    }

    /// The left button pressed at `from`, moved to `to` in `steps` steps, released.
    pub fn drag(&mut self, from: (f64, f64), to: (f64, f64), steps: usize) {
        let left = serde_json::json!({"button": "left", "buttons": 1, "clickCount": 1});
        self.mouse("mouseMoved", from.0, from.1, serde_json::json!({}));
        self.mouse("mousePressed", from.0, from.1, left.clone());
        for k in 1..=steps {
            let a = k as f64 / steps as f64;
            let (x, y) = (from.0 + a * (to.0 - from.0), from.1 + a * (to.1 - from.1));
            self.mouse("mouseMoved", x, y, left.clone());
        }
        self.mouse("mouseReleased", to.0, to.1, left);
    }

    /// A left click at (x, y).
    pub fn click(&mut self, x: f64, y: f64) {
        self.drag((x, y), (x, y), 0);
    }

    /// A click at the middle of the element `selector` (which must be there).
    pub fn click_on(&mut self, selector: &str) {
        let r = self.eval(&format!(
            "(() => {{ const b = document.querySelector({selector:?}).getBoundingClientRect(); \
             return [b.left + b.width / 2, b.top + b.height / 2]; }})()"
        ));
        self.click(r[0].as_f64().unwrap(), r[1].as_f64().unwrap());
    }

    /// A screenshot of the page, PNG bytes.
    pub fn screenshot_png(&mut self) -> Vec<u8> {
        let r = self.call(
            "Page.captureScreenshot",
            serde_json::json!({"format": "png"}),
        );
        base64::engine::general_purpose::STANDARD
            .decode(r["data"].as_str().unwrap())
            .unwrap()
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
