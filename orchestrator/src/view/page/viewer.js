// The swarm viewer: plays a run's frames on a canvas. /run.js (window.RUN) gives the frames the
// first picture needs; the others are asked for a chunk at a time (/api/frames?from=&to=) as
// the page plays or is scrubbed, and only a few chunks are kept. A live run's new frames come
// over server-sent events (/api/stream).
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
  let ended = RUN.ended;

  // The frames the page holds: tick index -> frame, kept a chunk of RUN.chunk ticks at a
  // time; at most KEEP_CHUNKS chunks (the least recently drawn go first), so a page's memory
  // does not grow with the run.
  const CHUNK = RUN.chunk;
  let legendShown = false; // legend() has run (frames kept before it wait for it)
  const KEEP_CHUNKS = 8;
  let count = RUN.count; // frames the run has (that the page knows of)
  const frames = new Map();
  const used = new Map(); // chunk -> when last drawn or received
  const pending = new Set(); // chunks asked for
  const askedAt = new Map(); // chunk -> `count` when it was last fetched
  let clock = 0, requests = 0;
  const chunkOf = (k) => Math.floor(k / CHUNK);
  // What the run has shown (the legend lists only that): the server's figure at load, grown
  // by the frames that come after (each says so when it grew).
  const seen = { states: new Set(), legend: new Set(), dead: false };
  function see(s) {
    if (!s) return false;
    const before = seen.states.size + seen.legend.size + seen.dead;
    s.states.forEach((x) => seen.states.add(x));
    s.legend.forEach((x) => seen.legend.add(x));
    seen.dead = seen.dead || s.dead;
    return seen.states.size + seen.legend.size + seen.dead !== before;
  }
  see(RUN.seen);
  function keep(k, f) {
    if (see(f.seen) && legendShown) legend();
    frames.set(k, f);
    used.set(chunkOf(k), ++clock);
  }
  RUN.frames.forEach((f, i) => keep(RUN.first + i, f));
  function evict(need) {
    while (used.size > KEEP_CHUNKS) {
      let old = null, at = Infinity;
      for (const [c, t] of used) if (!need.has(c) && t < at) { at = t; old = c; }
      if (old === null) return;
      used.delete(old); askedAt.delete(old);
      for (let k = old * CHUNK; k < (old + 1) * CHUNK; k++) frames.delete(k);
    }
  }
  function ask(c) {
    if (pending.has(c) || askedAt.get(c) === count || c < 0 || c * CHUNK >= count) return;
    pending.add(c); askedAt.set(c, count); requests++;
    fetch(`/api/frames?from=${c * CHUNK}&to=${(c + 1) * CHUNK}`)
      .then((r) => r.json())
      .then((list) => { list.forEach((f, i) => keep(c * CHUNK + i, f)); })
      .catch(() => { askedAt.delete(c); })
      .finally(() => { pending.delete(c); later(); });
  }
  // Frame k, or undefined after asking for its chunk.
  function frame(k) {
    const f = frames.get(k);
    if (f === undefined) ask(chunkOf(k));
    else used.set(chunkOf(k), ++clock);
    return f;
  }

  // Geometry: the canvas fills the window left of the side panel (SIDE_W px, viewer.css);
  // at zoom 1 the whole arena fits it less a margin, centred; y up. The view is the zoom
  // over that fit and the arena point at the canvas's centre (cx, cy). Tests project robots
  // with the same numbers (tests/tests/viewer.rs).
  const SIDE_W = 400, MARGIN = 10, MIN_CANVAS = 200;
  // Zoom bounds, the wheel's zoom per pixel of scroll, the buttons' step, and how far the
  // pointer moves before a press is a drag (not a click selecting a robot).
  const MIN_ZOOM = 0.5, MAX_ZOOM = 64, WHEEL_ZOOM = 0.002, BUTTON_ZOOM = 1.5, DRAG_PX = 4;
  const [AW, AH] = meta.arena;
  const view = { zoom: 1, cx: AW / 2, cy: AH / 2 };
  let scale = 1;
  function layout() {
    const w = Math.max(MIN_CANVAS, window.innerWidth - SIDE_W);
    const h = Math.max(MIN_CANVAS, window.innerHeight);
    // Setting a canvas's size clears it: only when it changed.
    if (canvas.width !== w) canvas.width = w;
    if (canvas.height !== h) canvas.height = h;
    const fit = Math.min((canvas.width - 2 * MARGIN) / AW, (canvas.height - 2 * MARGIN) / AH);
    scale = fit * view.zoom;
  }
  const px = (p) => [canvas.width / 2 + (p[0] - view.cx) * scale,
    canvas.height / 2 - (p[1] - view.cy) * scale];
  const arenaAt = (x, y) => [view.cx + (x - canvas.width / 2) / scale,
    view.cy - (y - canvas.height / 2) / scale];
  // A robot's disc on the page, in pixels, at any zoom (bodies show as the missions' marks:
  // a disc this size drawn over them would hide them).
  const ROBOT_PX = 5;
  const robotPx = () => ROBOT_PX;

  const q = new URLSearchParams(location.search);
  // The view from the URL (?zoom=Z&cx=X&cy=Y), as the wheel and a drag leave it.
  if (q.has("zoom")) view.zoom = Math.min(MAX_ZOOM, Math.max(MIN_ZOOM, parseFloat(q.get("zoom")) || 1));
  if (q.has("cx")) view.cx = parseFloat(q.get("cx")) || view.cx;
  if (q.has("cy")) view.cy = parseFloat(q.get("cy")) || view.cy;
  layout();
  let cur = 0;
  let pinned = q.has("tick");
  let playing = q.get("play") === "1";
  let selected = q.has("robot") ? parseInt(q.get("robot"), 10) : null;
  if (pinned) cur = parseInt(q.get("tick"), 10) || 0;
  else if (meta.live) cur = Math.max(0, count - 1);
  if (q.has("trail")) $("trail").value = q.get("trail");
  if (q.has("speed")) {
    const v = String(parseFloat(q.get("speed")) || 20), sel = $("speed");
    if (![...sel.options].some((o) => o.value === v)) sel.add(new Option(v + " ticks/s", v));
    sel.value = v;
  }

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

  // What the last picture drew (the page's own state, for tests: #state).
  let drawn = {};
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
    } else {
      ctx.restore();
      return;
    }
    drawn[kind] = (drawn[kind] || 0) + 1;
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

  // Robot i's messages this tick (recordings with deliveries): its senders, one entry per
  // message, and their payload bytes.
  function heardBy(f, i) {
    if (!f.heard) return null;
    return { senders: f.heard[i] || [], bytes: (f.heard_bytes || [])[i] || 0 };
  }

  // Colour of the lines from the robots the selected one heard this tick.
  const HEARD_RGB = [200, 0, 200];

  // The page's own colours: obstacles (not black: formation's final discs and hunt's free
  // evaders are), and the start region's tint and outline.
  const OBSTACLE_RGB = [150, 120, 90];
  const START_RGB = [120, 120, 255], START_ALPHA = 0.15, START_LINE_RGB = [80, 80, 200];

  function draw() {
    drawn = {};
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, canvas.width, canvas.height);
    const [ax, ay] = px([0, AH]);
    ctx.strokeStyle = "#000"; ctx.lineWidth = 2;
    ctx.strokeRect(ax, ay, AW * scale, AH * scale);
    if (meta.start_region_shown) {
      const sr = meta.start_region, [sx, sy] = px([sr[0], sr[3]]);
      ctx.fillStyle = rgb(START_RGB, START_ALPHA);
      ctx.fillRect(sx, sy, (sr[2] - sr[0]) * scale, (sr[3] - sr[1]) * scale);
      ctx.strokeStyle = rgb(START_LINE_RGB); ctx.lineWidth = 1;
      ctx.strokeRect(sx, sy, (sr[2] - sr[0]) * scale, (sr[3] - sr[1]) * scale);
    }
    ctx.fillStyle = rgb(OBSTACLE_RGB);
    for (const o of meta.obstacles) {
      ctx.beginPath();
      o.forEach((p, k) => { const [x, y] = px(p); k ? ctx.lineTo(x, y) : ctx.moveTo(x, y); });
      ctx.closePath(); ctx.fill();
    }
    for (const [c, r] of meta.discs) {
      const [x, y] = px(c);
      ctx.beginPath(); ctx.arc(x, y, r * scale, 0, 2 * Math.PI); ctx.fill();
    }
    if (!count) { status(null); return; }
    cur = Math.max(0, Math.min(cur, count - 1));
    // The chunks this picture needs stay; the page asks for the next one ahead of play.
    const trail = Math.max(0, parseInt($("trail").value, 10) || 0);
    const first = Math.max(0, cur - trail);
    const need = new Set();
    for (let c = chunkOf(first); c <= chunkOf(cur); c++) need.add(c);
    if (playing) { need.add(chunkOf(cur) + 1); frame(Math.min(count - 1, (chunkOf(cur) + 1) * CHUNK)); }
    const f = frame(cur);
    evict(need);
    if (!f) { status(null); return; }
    for (const m of f.layer) drawMark(m);
    // Trails: each robot's last `trail` ticks, coloured by its state then (the ticks the page
    // holds: a piece still on its way is drawn when it comes).
    ctx.lineWidth = 1;
    let prev = frame(first);
    for (let k = first + 1; k <= cur; k++) {
      const g = frame(k);
      if (prev && g) {
        for (let i = 0; i < meta.robots; i++) {
          const a = px(prev.poses[i]), b = px(g.poses[i]);
          ctx.strokeStyle = rgb(colour(i, g.states[i]), 0.5);
          ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
        }
      }
      prev = g;
    }
    if (selected !== null && selected < meta.robots) {
      const p = px(f.poses[selected]);
      ctx.strokeStyle = "rgba(0,120,0,0.8)"; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.arc(p[0], p[1], meta.comm_radius * scale, 0, 2 * Math.PI); ctx.stroke();
      const h = heardBy(f, selected);
      if (h) {
        // Who it heard: a line from each sender (where the sender is now).
        ctx.strokeStyle = rgb(HEARD_RGB); ctx.lineWidth = 2;
        for (const j of new Set(h.senders)) {
          const b = px(f.poses[j]);
          ctx.beginPath(); ctx.moveTo(b[0], b[1]); ctx.lineTo(p[0], p[1]); ctx.stroke();
        }
      } else {
        ctx.strokeStyle = "rgba(0,150,0,0.35)";
        for (const j of inRange(f, selected)) {
          const b = px(f.poses[j]);
          ctx.beginPath(); ctx.moveTo(p[0], p[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
        }
      }
    }
    const rp = robotPx();
    for (let i = 0; i < meta.robots; i++) {
      const [x, y] = px(f.poses[i]);
      if (f.alive[i]) {
        ctx.beginPath(); ctx.arc(x, y, rp, 0, 2 * Math.PI);
        ctx.fillStyle = rgb(colour(i, f.states[i])); ctx.fill();
        ctx.strokeStyle = "rgba(0,0,0,0.6)"; ctx.lineWidth = 1; ctx.stroke();
        const h = f.poses[i][2];
        ctx.beginPath(); ctx.moveTo(x, y);
        ctx.lineTo(x + (rp + 4) * Math.cos(h), y - (rp + 4) * Math.sin(h)); ctx.stroke();
      } else {
        // A dead robot: a black cross where it stands.
        ctx.strokeStyle = "#000"; ctx.lineWidth = 2; ctx.beginPath();
        ctx.moveTo(x - 5, y - 5); ctx.lineTo(x + 5, y + 5);
        ctx.moveTo(x + 5, y - 5); ctx.lineTo(x - 5, y + 5); ctx.stroke();
      }
      if (i === selected) {
        ctx.strokeStyle = "#000"; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.arc(x, y, rp + 4, 0, 2 * Math.PI); ctx.stroke();
      }
    }
    status(f);
  }

  function status(f) {
    $("scrub").max = Math.max(0, count - 1);
    $("scrub").value = cur;
    $("play").textContent = playing ? "pause" : "play";
    $("title").textContent = `run ${meta.run} (${meta.mission}, ${meta.robots} robots, seed ${meta.seed})`;
    const where = meta.live ? (ended ? "live run: ended" : "live run: running") : "replay";
    $("status").textContent = `${where}; ${count} of ${meta.max_ticks} ticks recorded` +
      (count && !f ? `; loading tick ${cur}...` : "");
    $("zoom").textContent = `zoom ${view.zoom.toFixed(2)}`;
    const state = {
      cur, tick: f ? f.tick : null, count, chunk: CHUNK, frames_held: frames.size,
      chunks_held: used.size, requests, pending: pending.size, marks: drawn, selected, heard: null,
      heap: performance.memory ? performance.memory.usedJSHeapSize : null,
      view: { zoom: view.zoom, cx: view.cx, cy: view.cy, scale, width: canvas.width, height: canvas.height },
      progress: f && meta.progress_label ? { label: meta.progress_label, done: f.done, total: f.total } : null,
      legend: null,
    };
    // Written last: the legend's place on the page once the text above it is set.
    const write = () => { state.legend = legendState(); $("state").textContent = JSON.stringify(state); };
    if (!f) { $("info").textContent = ""; write(); return; }
    const alive = f.alive.reduce((a, b) => a + b, 0);
    const r = f.radio;
    let t = `tick ${f.tick}\nrobots alive ${alive}/${meta.robots}\n`;
    // The mission's own figure, as the terminal shows it (formation: robots in place of the
    // live robots; search: targets found).
    if (meta.progress_label && (f.total > 0 || meta.progress_total > 0))
      t += `${meta.progress_label} ${f.done}/${f.total}\n`;
    t += `radio this tick: offered ${r.offered} delivered ${r.delivered}\n`;
    t += `  dropped: range ${r.dropped_range} occluded ${r.dropped_occluded} bandwidth ${r.dropped_bandwidth} loss ${r.dropped_loss}\n`;
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
        `  in radio range (${meta.comm_radius}): ${near.length} robots\n`;
      const h = heardBy(f, selected);
      if (h) {
        const from = [...new Set(h.senders)].sort((a, b) => a - b);
        const rows = [];
        for (let k = 0; k < from.length; k += 12) rows.push(from.slice(k, k + 12).join(", "));
        s += `  heard this tick: ${h.senders.length} messages, ${h.bytes} bytes\n` +
          `    from ${from.length} robots:\n    ${rows.join(",\n    ")}\n`;
        state.heard = { robot: selected, messages: h.senders.length, bytes: h.bytes, from };
      } else s += `    ${near.join(", ")}\n  heard this tick: not recorded (up --record-deliveries)\n`;
      s += `  events: ${ev.length ? ev.join("; ") : "none"}`;
    }
    $("robot").textContent = s;
    $("kill").disabled = !(meta.live && !ended && selected !== null && f.alive[selected]);
    write();
  }

  // A legend swatch (16 x 16 SVG) of `kind` in colour `c`, and the point of it that shows
  // the colour (tests sample the page's screenshot there).
  const SWATCH = {
    robot: [(c) => `<circle cx="8" cy="8" r="6" fill="${c}" stroke="rgba(0,0,0,0.6)"/>`, [8, 8]],
    Disc: [(c, o) => `<circle cx="8" cy="8" r="6" fill="${c}"${o ? ` stroke="${o}"` : ""}/>`, [8, 8]],
    Ring: [(c) => `<circle cx="8" cy="8" r="5" fill="none" stroke="${c}" stroke-width="2.5"/>`, [13, 8]],
    Circle: [(c) => `<circle cx="8" cy="8" r="6" fill="none" stroke="${c}" stroke-width="2"/>`, [14, 8]],
    Triangle: [(c) => `<polygon points="15,8 2,2 2,14" fill="${c}"/>`, [6, 8]],
    Path: [(c) => `<line x1="1" y1="15" x2="15" y2="1" stroke="${c}" stroke-width="3"/>`, [8, 8]],
    line: [(c) => `<line x1="1" y1="15" x2="15" y2="1" stroke="${c}" stroke-width="3"/>`, [8, 8]],
    area: [(c, o) => `<rect x="1" y="1" width="14" height="14" fill="${c}"${o ? ` stroke="${o}"` : ""}/>`, [8, 8]],
    cross: [() => `<path d="M3 3L13 13M13 3L3 13" stroke="#000" stroke-width="2.5"/>`, [8, 8]],
  };
  // The legend's rows as drawn: label, kind, colour (what the swatch shows at `probe`).
  let rows = [];
  function legend() {
    legendShown = true;
    rows = [];
    const row = (kind, colour, label, outline) => rows.push({ kind, colour, label, outline });
    for (const s of meta.states) if (seen.states.has(s.state)) row("robot", s.colour, s.name);
    if (!meta.states.length) row("robot", hsl(0, meta.robots), "robots, coloured by id");
    if (seen.dead) row("cross", [0, 0, 0], "dead robot");
    if (meta.obstacles.length || meta.discs.length) row("area", OBSTACLE_RGB, "obstacle");
    if (meta.start_region_shown) {
      // The tint over white, as the page shows it.
      const tint = START_RGB.map((c) => Math.round(255 + START_ALPHA * (c - 255)));
      row("area", tint, "start region", START_LINE_RGB);
    }
    if (meta.deliveries) row("line", HEARD_RGB, "heard by the selected robot this tick");
    meta.legend.forEach((e, k) => {
      if (!seen.legend.has(k)) return;
      const kind = Object.keys(e.mark)[0], v = e.mark[kind];
      const label = meta.live && !ended && e.running_label ? e.running_label : e.label;
      row(kind, v.fill || v.colour || [0, 0, 0], label, v.outline);
    });
    $("legend").innerHTML = rows.map((r) => {
      const [svg] = SWATCH[r.kind] || SWATCH.area;
      return `<div><svg viewBox="0 0 16 16">${svg(rgb(r.colour), r.outline && rgb(r.outline))}</svg>` +
        `<span>${r.label}</span></div>`;
    }).join("");
  }
  // The legend as the page shows it, with where each swatch shows its colour (page pixels).
  function legendState() {
    const svgs = document.querySelectorAll("#legend svg");
    return rows.map((r, i) => {
      const b = svgs[i] ? svgs[i].getBoundingClientRect() : { left: 0, top: 0 };
      const [, probe] = SWATCH[r.kind] || SWATCH.area;
      return { label: r.label, kind: r.kind, colour: r.colour, at: [b.left + probe[0], b.top + probe[1]] };
    });
  }

  let redraw = false;
  function later() {
    if (!redraw) { redraw = true; requestAnimationFrame(() => { redraw = false; draw(); }); }
  }

  $("play").onclick = () => { playing = !playing; pinned = false; last = null; later(); };
  $("back").onclick = () => { playing = false; pinned = true; cur = Math.max(0, cur - 1); later(); };
  $("fwd").onclick = () => { playing = false; pinned = true; cur = Math.min(count - 1, cur + 1); later(); };
  $("scrub").oninput = (e) => { pinned = true; cur = parseInt(e.target.value, 10); later(); };
  $("trail").oninput = later;
  $("follow").onchange = () => { if ($("follow").checked) { pinned = false; cur = count - 1; } later(); };
  document.addEventListener("keydown", (e) => {
    if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
    if (e.key === " ") { $("play").onclick(); e.preventDefault(); }
    if (e.key === "f") fit();
    if (e.key === "+" || e.key === "=") $("zoomin").onclick();
    if (e.key === "-") $("zoomout").onclick();
    if (e.key === "ArrowLeft") $("back").onclick();
    if (e.key === "ArrowRight") $("fwd").onclick();
  });
  // Zoom to `z`, keeping the arena point under canvas point (x, y) where it is.
  function setZoom(z, x, y) {
    const a = arenaAt(x, y);
    view.zoom = Math.min(MAX_ZOOM, Math.max(MIN_ZOOM, z));
    layout();
    const b = arenaAt(x, y);
    view.cx += a[0] - b[0]; view.cy += a[1] - b[1];
    later();
  }
  function fit() { view.zoom = 1; view.cx = AW / 2; view.cy = AH / 2; layout(); later(); }
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const b = canvas.getBoundingClientRect();
    setZoom(view.zoom * Math.exp(-e.deltaY * WHEEL_ZOOM), e.clientX - b.left, e.clientY - b.top);
  }, { passive: false });
  // A press on the canvas: a drag pans, a click (it moved less than DRAG_PX) selects.
  let press = null;
  canvas.addEventListener("mousedown", (e) => {
    if (e.button !== 0) return;
    press = { x: e.clientX, y: e.clientY, cx: view.cx, cy: view.cy, drag: false };
    e.preventDefault();
  });
  window.addEventListener("mousemove", (e) => {
    if (!press) return;
    const dx = e.clientX - press.x, dy = e.clientY - press.y;
    if (!press.drag && Math.hypot(dx, dy) < DRAG_PX) return;
    press.drag = true; canvas.classList.add("dragging");
    view.cx = press.cx - dx / scale; view.cy = press.cy + dy / scale;
    later();
  });
  window.addEventListener("mouseup", (e) => {
    if (!press) return;
    const p = press; press = null; canvas.classList.remove("dragging");
    if (!p.drag) pick(e);
  });
  // Selects the robot nearest the click (within its disc and 10 px more), or none.
  function pick(e) {
    const f = frames.get(cur); if (!f) return;
    const b = canvas.getBoundingClientRect(), x = e.clientX - b.left, y = e.clientY - b.top;
    const reach = robotPx() + 10;
    let best = null, bd = reach * reach;
    f.poses.forEach((p, i) => {
      const [u, v] = px(p), d = (u - x) * (u - x) + (v - y) * (v - y);
      if (d < bd) { bd = d; best = i; }
    });
    selected = best; later();
  }
  $("fit").onclick = fit;
  $("zoomin").onclick = () => setZoom(view.zoom * BUTTON_ZOOM, canvas.width / 2, canvas.height / 2);
  $("zoomout").onclick = () => setZoom(view.zoom / BUTTON_ZOOM, canvas.width / 2, canvas.height / 2);
  window.addEventListener("resize", () => { layout(); later(); });
  $("kill").onclick = () => {
    if (selected === null) return;
    const r = selected;
    const token = document.querySelector('meta[name="swarm-kill-token"]').content;
    fetch("/api/kill?robot=" + r, { method: "POST", headers: { "X-Swarm-Token": token } })
      .then((resp) => resp.text()).then((t) => { $("killmsg").textContent = t; })
      .catch((err) => { $("killmsg").textContent = "kill failed: " + err; });
  };

  // Playing: `speed` ticks per second of the recording; it waits at a tick whose chunk is
  // still on its way.
  let last = null;
  function tick(now) {
    if (playing && count) {
      if (last !== null) {
        const speed = parseFloat($("speed").value);
        const steps = Math.floor(((now - last) / 1000) * speed);
        if (steps > 0) {
          let to = Math.min(count - 1, cur + steps);
          while (to > cur && !frames.has(to)) { frame(to); to--; }
          cur = to;
          last = now;
          if (cur === count - 1 && (ended || !meta.live)) playing = false;
          draw();
        }
      } else last = now;
    } else last = null;
    requestAnimationFrame(tick);
  }

  if (meta.live && !ended) {
    const es = new EventSource("/api/stream?from=" + count);
    es.addEventListener("frame", (e) => {
      const f = JSON.parse(e.data);
      if (see(f.seen)) legend();
      count = Math.max(count, f.tick + 1);
      // Kept when its chunk is held or is the newest (the one a following page shows).
      if (used.has(chunkOf(f.tick)) || chunkOf(f.tick) >= chunkOf(cur)) keep(f.tick, f);
      if (!pinned && !playing && $("follow").checked) cur = count - 1;
      later();
    });
    es.addEventListener("end", () => { ended = true; es.close(); legend(); later(); });
    es.onerror = () => { if (ended) es.close(); };
  }
  legend();
  draw();
  requestAnimationFrame(tick);
})();
