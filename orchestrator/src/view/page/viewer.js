// The swarm viewer: plays a run's frames (window.RUN, from /run.js) on a canvas; a live run's
// further frames come over server-sent events (/api/stream).
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const canvas = $("arena");
  const ctx = canvas.getContext("2d");
  if (!window.RUN) {
    $("status").textContent = window.RUN_ERROR
      ? "error: " + window.RUN_ERROR
      : "waiting for the run's recording... (reload in a moment)";
    if (!window.RUN_ERROR) setTimeout(() => location.reload(), 500);
    return;
  }
  const meta = RUN.meta;
  const frames = RUN.frames;
  let ended = RUN.ended;

  // Geometry: the arena fills the canvas width less a margin, y up. Tests project robots
  // with the same numbers (tests/tests/viewer.rs).
  const CANVAS_W = 800, MARGIN = 10;
  const scale = (CANVAS_W - 2 * MARGIN) / meta.arena[0];
  canvas.width = CANVAS_W;
  canvas.height = Math.round(2 * MARGIN + meta.arena[1] * scale);
  const px = (p) => [MARGIN + p[0] * scale, MARGIN + (meta.arena[1] - p[1]) * scale];
  const ROBOT_PX = 5;

  const q = new URLSearchParams(location.search);
  let cur = 0;
  let pinned = q.has("tick");
  let playing = q.get("play") === "1";
  let selected = q.has("robot") ? parseInt(q.get("robot"), 10) : null;
  if (pinned) cur = parseInt(q.get("tick"), 10) || 0;
  else if (meta.live) cur = Math.max(0, frames.length - 1);
  if (q.has("trail")) $("trail").value = q.get("trail");

  const rgb = (c, a) => a === undefined ? `rgb(${c[0]},${c[1]},${c[2]})`
    : `rgba(${c[0]},${c[1]},${c[2]},${a})`;
  function hsl(i, n) {
    // As run.svg colours robots by id.
    const h = (i / Math.max(1, n)) * 6, s = 0.65, l = 0.45;
    const c = (1 - Math.abs(2 * l - 1)) * s, x = c * (1 - Math.abs((h % 2) - 1)), m = l - c / 2;
    const t = [[c, x, 0], [x, c, 0], [0, c, x], [0, x, c], [x, 0, c], [c, 0, x]][Math.min(5, Math.floor(h))];
    return t.map((v) => Math.floor((v + m) * 255));
  }
  function colour(i, state) {
    if (!meta.states.length) return hsl(i, meta.robots);
    const d = meta.states.find((s) => s.state === state) || meta.states[0];
    return d.colour;
  }
  function stateName(s) {
    const d = meta.states.find((x) => x.state === s);
    return d ? d.name : String(s);
  }

  function drawMark(m) {
    const kind = Object.keys(m)[0], v = m[kind];
    ctx.save();
    if (kind === "Disc") {
      const [x, y] = px(v.at);
      ctx.beginPath(); ctx.arc(x, y, v.px, 0, 2 * Math.PI);
      ctx.fillStyle = rgb(v.fill); ctx.fill();
      if (v.outline) { ctx.strokeStyle = rgb(v.outline); ctx.lineWidth = 1; ctx.stroke(); }
    } else if (kind === "Ring") {
      const [x, y] = px(v.at);
      ctx.beginPath(); ctx.arc(x, y, v.px, 0, 2 * Math.PI);
      ctx.strokeStyle = rgb(v.colour); ctx.lineWidth = v.width; ctx.stroke();
    } else if (kind === "Circle") {
      const [x, y] = px(v.at);
      ctx.beginPath(); ctx.arc(x, y, Math.max(1, v.radius * scale), 0, 2 * Math.PI);
      ctx.strokeStyle = rgb(v.colour); ctx.lineWidth = 1; ctx.stroke();
    } else if (kind === "Triangle") {
      // Tip and base corners found in arena units, so the canvas's y flip applies to them too.
      const l = v.px / scale, h = v.heading;
      const at = (a, r) => px([v.at[0] + r * Math.cos(h + a), v.at[1] + r * Math.sin(h + a)]);
      const [t, b1, b2] = [at(0, l * 0.6), at(2.5, l * 0.5), at(-2.5, l * 0.5)];
      ctx.beginPath(); ctx.moveTo(t[0], t[1]); ctx.lineTo(b1[0], b1[1]); ctx.lineTo(b2[0], b2[1]);
      ctx.closePath(); ctx.fillStyle = rgb(v.fill); ctx.fill();
    } else if (kind === "Path" && v.points.length) {
      ctx.beginPath();
      v.points.forEach((p, k) => { const [x, y] = px(p); k ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
      ctx.strokeStyle = rgb(v.colour); ctx.lineWidth = 2; ctx.stroke();
    }
    ctx.restore();
  }

  function inRange(f, i) {
    const p = f.poses[i], r = meta.comm_radius, out = [];
    for (let j = 0; j < f.poses.length; j++) {
      if (j === i || !f.alive[j]) continue;
      const dx = f.poses[j][0] - p[0], dy = f.poses[j][1] - p[1];
      if (dx * dx + dy * dy <= r * r) out.push(j);
    }
    return out;
  }

  function draw() {
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, canvas.width, canvas.height);
    const [ax, ay] = px([0, meta.arena[1]]);
    ctx.strokeStyle = "#000"; ctx.lineWidth = 2;
    ctx.strokeRect(ax, ay, meta.arena[0] * scale, meta.arena[1] * scale);
    const sr = meta.start_region, [sx, sy] = px([sr[0], sr[3]]);
    ctx.fillStyle = "rgba(120,120,255,0.15)";
    ctx.fillRect(sx, sy, (sr[2] - sr[0]) * scale, (sr[3] - sr[1]) * scale);
    ctx.strokeStyle = "rgb(80,80,200)"; ctx.lineWidth = 1;
    ctx.strokeRect(sx, sy, (sr[2] - sr[0]) * scale, (sr[3] - sr[1]) * scale);
    ctx.fillStyle = "rgba(0,0,0,0.85)";
    for (const o of meta.obstacles) {
      ctx.beginPath();
      o.forEach((p, k) => { const [x, y] = px(p); k ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
      ctx.closePath(); ctx.fill();
    }
    if (!frames.length) { status(); return; }
    cur = Math.max(0, Math.min(cur, frames.length - 1));
    const f = frames[cur];
    for (const m of f.layer) drawMark(m);
    // Trails: each robot's last `trail` ticks, coloured by its state then.
    const trail = Math.max(0, parseInt($("trail").value, 10) || 0);
    const first = Math.max(0, cur - trail);
    ctx.lineWidth = 1;
    for (let i = 0; i < meta.robots; i++) {
      for (let k = first + 1; k <= cur; k++) {
        const a = px(frames[k - 1].poses[i]), b = px(frames[k].poses[i]);
        ctx.strokeStyle = rgb(colour(i, frames[k].states[i]), 0.5);
        ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
      }
    }
    if (selected !== null && selected < meta.robots) {
      const p = px(f.poses[selected]);
      ctx.strokeStyle = "rgba(0,120,0,0.8)"; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.arc(p[0], p[1], meta.comm_radius * scale, 0, 2 * Math.PI); ctx.stroke();
      ctx.strokeStyle = "rgba(0,150,0,0.35)";
      for (const j of inRange(f, selected)) {
        const b = px(f.poses[j]);
        ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
      }
    }
    for (let i = 0; i < meta.robots; i++) {
      const [x, y] = px(f.poses[i]);
      if (f.alive[i]) {
        ctx.beginPath(); ctx.arc(x, y, ROBOT_PX, 0, 2 * Math.PI);
        ctx.fillStyle = rgb(colour(i, f.states[i])); ctx.fill();
        ctx.strokeStyle = "rgba(0,0,0,0.6)"; ctx.lineWidth = 1; ctx.stroke();
        const h = f.poses[i][2];
        ctx.beginPath(); ctx.moveTo(x, y);
        ctx.lineTo(x + 9 * Math.cos(h), y - 9 * Math.sin(h)); ctx.stroke();
      } else {
        // A dead robot: a black cross where it stands.
        ctx.strokeStyle = "#000"; ctx.lineWidth = 2; ctx.beginPath();
        ctx.moveTo(x - 5, y - 5); ctx.lineTo(x + 5, y + 5);
        ctx.moveTo(x + 5, y - 5); ctx.lineTo(x - 5, y + 5); ctx.stroke();
      }
      if (i === selected) {
        ctx.strokeStyle = "#000"; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.arc(x, y, ROBOT_PX + 4, 0, 2 * Math.PI); ctx.stroke();
      }
    }
    status();
  }

  function status() {
    const n = frames.length;
    const f = frames[cur];
    $("scrub").max = Math.max(0, n - 1);
    $("scrub").value = cur;
    $("play").textContent = playing ? "pause" : "play";
    $("title").textContent = `run ${meta.run} (${meta.mission}, ${meta.robots} robots, seed ${meta.seed})`;
    const where = meta.live ? (ended ? "live run: ended" : "live run: running") : "replay";
    $("status").textContent = `${where}; ${n} of ${meta.max_ticks} ticks recorded`;
    if (!f) { $("info").textContent = ""; return; }
    const alive = f.alive.reduce((a, b) => a + b, 0);
    const r = f.radio;
    let t = `tick ${f.tick}\nrobots alive ${alive}/${meta.robots}\n`;
    if (meta.progress_total > 0 && meta.progress_label)
      t += `${meta.progress_label} ${f.done}/${meta.progress_total}\n`;
    t += `radio this tick: offered ${r.offered} delivered ${r.delivered}\n`;
    t += `  dropped: range ${r.dropped_range} loss ${r.dropped_loss} unlinked ${r.dropped_unlinked}\n`;
    t += `events this tick ${f.events.length}`;
    $("info").textContent = t;
    let s = "";
    if (selected !== null && selected < meta.robots) {
      const p = f.poses[selected];
      const near = inRange(f, selected);
      const ev = f.events.filter((e) => Object.values(e)[0].robot === selected)
        .map((e) => Object.keys(e)[0] + (Object.values(e)[0].cause ? ": " + Object.values(e)[0].cause : ""));
      s = `robot ${selected} ${f.alive[selected] ? "alive" : "DEAD"}\n` +
        `  at (${p[0].toFixed(1)}, ${p[1].toFixed(1)}) heading ${p[2].toFixed(2)}\n` +
        `  state ${stateName(f.states[selected])}\n` +
        `  in radio range (${meta.comm_radius}): ${near.length} robots\n    ${near.join(", ")}\n` +
        `  events: ${ev.length ? ev.join("; ") : "none"}`;
    }
    $("robot").textContent = s;
    $("kill").disabled = !(meta.live && !ended && selected !== null && f.alive[selected]);
  }

  function legend() {
    let h = "";
    for (const s of meta.states)
      h += `<div><span class="swatch" style="background:${rgb(s.colour)}"></span>${s.name}</div>`;
    if (!meta.states.length) h += `<div>robots coloured by id</div>`;
    h += `<div><b>&times;</b> dead robot</div>`;
    for (const e of meta.legend) {
      const v = Object.values(e.mark)[0];
      const c = v.fill || v.colour || [0, 0, 0];
      h += `<div><span class="swatch" style="background:${rgb(c)}"></span>${e.label}</div>`;
    }
    $("legend").innerHTML = h;
  }

  let redraw = false;
  function later() {
    if (!redraw) { redraw = true; requestAnimationFrame(() => { redraw = false; draw(); }); }
  }

  $("play").onclick = () => { playing = !playing; pinned = false; last = null; later(); };
  $("back").onclick = () => { playing = false; pinned = true; cur = Math.max(0, cur - 1); later(); };
  $("fwd").onclick = () => { playing = false; pinned = true; cur = Math.min(frames.length - 1, cur + 1); later(); };
  $("scrub").oninput = (e) => { pinned = true; cur = parseInt(e.target.value, 10); later(); };
  $("trail").oninput = later;
  $("follow").onchange = () => { if ($("follow").checked) { pinned = false; cur = frames.length - 1; } later(); };
  document.addEventListener("keydown", (e) => {
    if (e.key === " ") { $("play").onclick(); e.preventDefault(); }
    if (e.key === "ArrowLeft") $("back").onclick();
    if (e.key === "ArrowRight") $("fwd").onclick();
  });
  canvas.onclick = (e) => {
    const f = frames[cur]; if (!f) return;
    const b = canvas.getBoundingClientRect(), x = e.clientX - b.left, y = e.clientY - b.top;
    let best = null, bd = 15 * 15;
    f.poses.forEach((p, i) => {
      const [u, v] = px(p), d = (u - x) * (u - x) + (v - y) * (v - y);
      if (d < bd) { bd = d; best = i; }
    });
    selected = best; later();
  };
  $("kill").onclick = () => {
    if (selected === null) return;
    const r = selected;
    fetch("/api/kill?robot=" + r, { method: "POST" })
      .then((resp) => resp.text()).then((t) => { $("killmsg").textContent = t; })
      .catch((err) => { $("killmsg").textContent = "kill failed: " + err; });
  };

  // Playing: `speed` ticks per second of the recording.
  let last = null;
  function tick(now) {
    if (playing && frames.length) {
      if (last !== null) {
        const speed = parseFloat($("speed").value);
        const steps = Math.floor(((now - last) / 1000) * speed);
        if (steps > 0) {
          cur = Math.min(frames.length - 1, cur + steps);
          last = now;
          if (cur === frames.length - 1 && (ended || !meta.live)) playing = false;
          draw();
        }
      } else last = now;
    } else last = null;
    requestAnimationFrame(tick);
  }

  if (meta.live && !ended) {
    const es = new EventSource("/api/stream?from=" + frames.length);
    es.addEventListener("frame", (e) => {
      frames.push(JSON.parse(e.data));
      if (!pinned && !playing && $("follow").checked) cur = frames.length - 1;
      later();
    });
    es.addEventListener("end", () => { ended = true; es.close(); later(); });
    es.onerror = () => { if (ended) es.close(); };
  }
  legend();
  draw();
  requestAnimationFrame(tick);
})();
