// The page: the simulation in real time at the scene's dt (clock.js), drawn with WebGL2
// (render-gl.js) or Canvas 2D where WebGL2 is missing (render-2d.js), the pointer as the
// haptic device, and what goes wrong shown as it happens.

import { Simulation, EFFECTS } from "./simulation.js";
import { Clock } from "./clock.js";
import { GlRenderer } from "./render-gl.js";
import { CanvasRenderer } from "./render-2d.js";

const query = new URLSearchParams(location.search);
const sim = await Simulation.load(query.get("simd") !== "0");
const $ = (id) => document.getElementById(id);
const view = $("view");
const renderer = makeRenderer();
const clock = new Clock();

// How long a warning stays up after it last happened, ms.
const WARNING_MS = 1000;
// Some strand rolled back at every step for this long: the page says the simulation is stuck
// (a rolled-back strand keeps its last good state, so nothing moves it on).
const STUCK_MS = 1000;
// Pixels within which a press grabs a node.
const GRAB_PIXELS = 12;

const state = {
  status: null,
  camera: { yaw: 0.5, pitch: 0.2, distance: 0.6, centre: [0, 0, 0] },
  hand: null, // { depth, x, y }
  forces: [], // [simulated s, |F|]
  slips: [], // [simulated s, |F| held before]
  drawMs: 0,
  drawnAt: -Infinity,
  error: "",
  followers: new Float32Array(),
  withFollowers: true,
  loaded: "",
  warnings: new Map(), // kind -> { text, until }
  stuckSince: null,
  stuckFewest: 0, // fewest strands rolled back in one step since stuckSince
  slipped: null, // { at: [x, y, z], force }
};

function makeRenderer() {
  if (query.get("renderer") !== "2d") {
    try {
      return new GlRenderer(view);
    } catch (e) {
      console.warn(`WebGL2 unavailable (${e.message}): drawing with Canvas 2D`);
    }
  }
  return new CanvasRenderer(view);
}

function showError(e) {
  state.error = e ? String(e.message ?? e) : "";
  $("error").textContent = state.error;
}

// ---- camera: orbit about a centre, perspective with a 0.8 rad vertical field of view ----
const HALF_FOV = 0.4;
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

function camera() {
  const { yaw, pitch, distance, centre } = state.camera;
  const forward = [-Math.cos(pitch) * Math.sin(yaw), -Math.sin(pitch), -Math.cos(pitch) * Math.cos(yaw)];
  const right = [Math.cos(yaw), 0, -Math.sin(yaw)];
  const up = [
    right[1] * forward[2] - right[2] * forward[1],
    right[2] * forward[0] - right[0] * forward[2],
    right[0] * forward[1] - right[1] * forward[0],
  ];
  const eye = centre.map((c, i) => c - forward[i] * distance);
  const width = view.width, height = view.height;
  const focal = height / (2 * Math.tan(HALF_FOV));
  const near = distance / 50, far = distance * 20;
  // Column-major view-projection: clip = P · V · world.
  const fy = 1 / Math.tan(HALF_FOV), fx = fy * (height / width);
  const a = (far + near) / (near - far), b = (2 * far * near) / (near - far);
  const rows = [right, up, forward];
  const t = rows.map((r) => -dot(r, eye));
  const viewProjection = new Float32Array(16);
  for (let c = 0; c < 3; c++) {
    viewProjection[4 * c + 0] = fx * right[c];
    viewProjection[4 * c + 1] = fy * up[c];
    viewProjection[4 * c + 2] = -a * forward[c];
    viewProjection[4 * c + 3] = forward[c];
  }
  viewProjection[12] = fx * t[0];
  viewProjection[13] = fy * t[1];
  viewProjection[14] = -a * t[2] + b;
  viewProjection[15] = t[2];
  return {
    eye, width, height, viewProjection,
    // Pixel position (y down) and depth of world point p.
    project(p) {
      const d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
      const z = dot(d, forward);
      return [width / 2 + (focal * dot(d, right)) / z, height / 2 - (focal * dot(d, up)) / z, z];
    },
    // The world point under pixel (x, y) at depth z.
    unproject(x, y, z) {
      const u = ((x - width / 2) * z) / focal, v = (-(y - height / 2) * z) / focal;
      return [0, 1, 2].map((i) => eye[i] + forward[i] * z + right[i] * u + up[i] * v);
    },
    pixels: (length, z) => (length * focal) / z,
  };
}

// Frames the hair as it hangs: its nodes now and, unless shape preservation holds the groom
// up, each strand hanging straight down from its root. Only the hair: a large fitted head or
// a floor would push the hair into a corner of the view.
function frameScene() {
  const { points, offsets } = sim.positions();
  const hangs = !sim.status().effects.includes("shape");
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  const add = (p) => p.forEach((x, a) => { lo[a] = Math.min(lo[a], x); hi[a] = Math.max(hi[a], x); });
  for (let s = 0; s + 1 < offsets.length; s++) {
    const first = offsets[s], last = offsets[s + 1];
    let length = 0;
    for (let n = first; n < last; n++) {
      const p = [points[3 * n], points[3 * n + 1], points[3 * n + 2]];
      add(p);
      if (n > first) length += Math.hypot(p[0] - points[3 * n - 3], p[1] - points[3 * n - 2], p[2] - points[3 * n - 1]);
    }
    if (hangs && last > first) add([points[3 * first], points[3 * first + 1] - length, points[3 * first + 2]]);
  }
  if (!isFinite(lo[0])) return;
  const centre = lo.map((l, a) => (l + hi[a]) / 2);
  const size = Math.max(...hi.map((h, a) => h - lo[a]), 0.02);
  Object.assign(state.camera, { centre, distance: (0.6 * size) / Math.tan(HALF_FOV), yaw: 0.5, pitch: 0.2 });
  // Hair that sits above its head (a mohawk, an updo) is seen from above, and the camera
  // stays out of the head.
  const head = sim.status().colliders.find((c) => c.sphere)?.sphere;
  if (!head) return;
  const up = centre.map((x, a) => x - head.centre[a]);
  const above = up[1] / (Math.hypot(...up) || 1);
  if (above > 0.3) state.camera.pitch = Math.min(1.2, 0.2 + above);
  const eye = camera().eye;
  const inside = head.radius * 1.3 - Math.hypot(...eye.map((x, a) => x - head.centre[a]));
  if (inside > 0) state.camera.distance += inside;
}

// The hair's centre and radius (for the shading's depth cue), from its nodes.
function volume(points) {
  const n = points.length / 3;
  if (!n) return [[0, 0, 0], 1];
  const c = [0, 0, 0];
  for (let i = 0; i < points.length; i += 3) for (let a = 0; a < 3; a++) c[a] += points[i + a] / n;
  let r = 0;
  for (let i = 0; i < points.length; i += 3) r = Math.max(r, Math.hypot(points[i] - c[0], points[i + 1] - c[1], points[i + 2] - c[2]));
  return [c, Math.max(r, 1e-3)];
}

// ---- drawing ----
function draw() {
  const w = view.clientWidth, h = view.clientHeight;
  if (view.width !== w || view.height !== h) {
    view.width = w;
    view.height = h;
  }
  const { points, offsets } = sim.positions();
  const frame = {
    camera: camera(),
    points: points.slice(),
    offsets: offsets.slice(),
    flags: sim.strandFlags().slice(),
    followers: state.followers,
    withFollowers: state.withFollowers,
    headRotation: state.status.head.rotation,
    colliders: state.status.colliders,
    volume: volume(points),
    strandWidth: Math.max(1, Math.min(3, 2.2 * Math.sqrt(25 / Math.max(25, offsets.length - 1 + state.followers.length / 4)) * (view.height / 800) + 0.6)),
  };
  renderer.draw(frame);
  drawHand(frame.camera);
}

// The hand over the picture (a 2-D overlay): the held node, the force as an arrow, the
// coupling's spring as a line from the node to the hand when it stretches, and after a slip
// the node and the hand joined by a dashed line.
function drawHand(cam) {
  const overlay = $("overlay");
  if (overlay.width !== view.width || overlay.height !== view.height) {
    overlay.width = view.width;
    overlay.height = view.height;
  }
  const ctx = overlay.getContext("2d");
  ctx.clearRect(0, 0, overlay.width, overlay.height);
  const s = state.status;
  if (!s.grab_target || !s.held) return;
  const [x, y] = cam.project(s.grab_target);
  const [nx, ny] = cam.project(s.held.position);
  if (s.grab === "slipped") {
    ctx.strokeStyle = "#ff4060";
    ctx.setLineDash([6, 4]);
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(x, y);
    ctx.lineTo(nx, ny);
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.beginPath();
    ctx.arc(nx, ny, 6, 0, 2 * Math.PI);
    ctx.moveTo(x - 6, y - 6);
    ctx.lineTo(x + 6, y + 6);
    ctx.moveTo(x + 6, y - 6);
    ctx.lineTo(x - 6, y + 6);
    ctx.stroke();
    ctx.fillStyle = "#ff4060";
    ctx.font = "13px system-ui, sans-serif";
    ctx.fillText("slipped: press again to re-grab", x + 10, y - 10);
    return;
  }
  // The spring between the hand and the node, drawn once it stretches past a few pixels: a
  // strand pulled taut, or a node that lags a fast hand.
  if (Math.hypot(nx - x, ny - y) > 3) {
    ctx.strokeStyle = "#6cf8";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.moveTo(x, y);
    ctx.lineTo(nx, ny);
    ctx.stroke();
  }
  const f = s.grab_force;
  const magnitude = Math.hypot(...f);
  // The arrow's length grows with the force's logarithm: forces span decades.
  const length = magnitude > 0 ? 20 + 12 * Math.max(0, Math.log10(magnitude / 1e-7)) : 0;
  const tip = cam.project(s.grab_target.map((t, i) => t + (f[i] / (magnitude || 1)) * 1e-3));
  const dir = [tip[0] - x, tip[1] - y];
  const dl = Math.hypot(...dir) || 1;
  ctx.strokeStyle = "#6cf";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.arc(x, y, 5, 0, 2 * Math.PI);
  ctx.moveTo(x, y);
  ctx.lineTo(x + (dir[0] / dl) * length, y + (dir[1] / dl) * length);
  ctx.stroke();
}

// |F| over the last 2 s of simulated time, slips marked.
function drawPlot() {
  const plot = $("plot");
  const p = plot.getContext("2d");
  const now = state.status.time;
  p.fillStyle = "#111";
  p.fillRect(0, 0, plot.width, plot.height);
  state.forces = state.forces.filter(([t]) => t <= now && now - t <= 2);
  state.slips = state.slips.filter(([t]) => t <= now && now - t <= 2);
  const top = Math.max(1e-9, ...state.forces.map(([, f]) => f), ...state.slips.map(([, f]) => f));
  const x = (t) => plot.width * (1 - (now - t) / 2);
  const y = (f) => plot.height * (1 - f / top);
  p.strokeStyle = "#6cf";
  p.beginPath();
  state.forces.forEach(([t, f], i) => (i === 0 ? p.moveTo(x(t), y(f)) : p.lineTo(x(t), y(f))));
  p.stroke();
  p.fillStyle = "#ff4060";
  p.strokeStyle = "#ff4060";
  for (const [t, f] of state.slips) {
    p.beginPath();
    p.moveTo(x(t), 0);
    p.lineTo(x(t), plot.height);
    p.stroke();
    p.fillText(`slip ${f.toExponential(1)} N`, Math.min(x(t) + 3, plot.width - 70), 22);
  }
  p.fillStyle = "#aaa";
  p.fillText(`${top.toExponential(2)} N`, 4, 10);
}

// ---- warnings: what went wrong, as it happens ----
function warn(kind, text, now) {
  state.warnings.set(kind, { text, until: now + WARNING_MS });
}

function readEvents(now) {
  const e = sim.events();
  const s = state.status;
  if (e.rolled_back_max > 0) warn("rolled-back", `${e.rolled_back_max} of ${s.strands} strands rolled back to their last good state`, now);
  if (e.max_stretch > 0.01) {
    const off = s.effects.includes("inextensibility") ? "" : " (inextensibility is off)";
    const amount = e.max_stretch >= 1 ? `×${(1 + e.max_stretch).toFixed(1)}` : `by ${(100 * e.max_stretch).toFixed(1)} %`;
    warn("stretch", `strands stretched ${amount}${off}`, now);
  }
  if (e.cap_hits_max > 0) warn("cap", `the projection hit its iteration cap on ${e.cap_hits_max} strands`, now);
  if (e.slipped_at !== null) {
    state.slips.push([s.time, e.slipped_at]);
    warn("slip", `the grab slipped, holding ${e.slipped_at.toExponential(2)} N (limit ${s.grab_limit} N): press again to re-grab`, now);
  }
  const stuck = e.steps > 0 && e.rolled_back_min > 0;
  if (!stuck && e.steps > 0) state.stuckSince = null;
  else if (stuck && state.stuckSince === null) [state.stuckSince, state.stuckFewest] = [now, e.rolled_back_min];
  else if (stuck) state.stuckFewest = Math.min(state.stuckFewest, e.rolled_back_min);
  return e;
}

function showWarnings(now) {
  const lines = [];
  for (const [kind, w] of state.warnings) {
    if (w.until < now) state.warnings.delete(kind);
    else lines.push(w.text);
  }
  const stuck = state.stuckSince !== null && now - state.stuckSince >= STUCK_MS;
  $("stuck").hidden = !stuck;
  if (stuck) {
    const n = state.status ? state.status.strands : 0;
    const who = state.stuckFewest >= n ? "Every strand has" : `${state.stuckFewest} or more of ${n} strands have`;
    $("stuck-text").textContent = `${who} been rolled back at every step for ${((now - state.stuckSince) / 1000).toFixed(1)} s: the simulation is stuck.`;
  }
  const text = lines.join("\n");
  if ($("warnings").textContent !== text) $("warnings").textContent = text;
  $("warnings").hidden = lines.length === 0;
}

// ---- the frame ----
function numbers() {
  const s = state.status;
  const n = clock.numbers(s.dt);
  return {
    ...n,
    steps: s.steps,
    time: s.time,
    state_hash: s.state_hash,
    grab_force: s.grab_force,
    grab: s.grab,
    grab_target: s.grab_target,
    grab_limit: s.grab_limit,
    grab_coupling: s.grab_coupling,
    held: s.held,
    solver: s.solver,
    effects: s.effects,
    unusable: s.unusable,
    scene: s.scene,
    source: s.source,
    strands: s.strands,
    followers: s.followers,
    drawn_followers: state.withFollowers ? s.followers : 0,
    report: s.report,
    draw_ms_per_frame: state.drawMs,
    module: sim.module,
    renderer: renderer.kind,
    warnings: [...state.warnings.values()].map((w) => w.text),
    plotted: { samples: state.forces.length, max: Math.max(0, ...state.forces.map(([, f]) => f)) },
    slips: state.slips.length,
    stuck: !$("stuck").hidden,
    loaded: state.loaded,
  };
}

function showNumbers() {
  const n = numbers();
  const s = state.status;
  $("numbers").textContent =
    `time ${s.time.toFixed(3)} s, steps ${n.steps}\n` +
    `${n.us_per_sim_ms.toFixed(0)} µs compute / simulated ms (last second)\n` +
    `${n.steps_per_s.toFixed(0)} steps/s, real-time ratio ${n.realtime_ratio.toFixed(2)}\n` +
    `lag ${(1000 * n.lag_s).toFixed(0)} ms, dropped ${n.dropped_s.toFixed(2)} s\n` +
    `${n.frames_per_s.toFixed(0)} frames/s, ${n.draw_ms_per_frame.toFixed(1)} ms drawing each\n` +
    `${s.strands} strands + ${n.drawn_followers} followers drawn, ${s.nodes} nodes\n` +
    `${sim.module.includes("simd") ? "WebAssembly SIMD" : "WebAssembly (no SIMD)"}, ${renderer.kind}\n` +
    `grab ${s.grab}` + (s.grab === "held" ? `, ${Math.hypot(...s.grab_force).toExponential(2)} N` : "") +
    ` (spring ${s.grab_coupling[0]} N/m, slips above ${s.grab_limit} N)`;
  $("hash").textContent = `hash ${n.state_hash}`;
  $("hash-note").textContent = s.hair_hair_dropped
    ? "not the native hash: this scene has hair–hair (SPH), which runs in `hairsim run`, not here"
    : "the native hash of these steps (`hairsim run --steps N --json`)";
  $("clock").textContent = n.slow_motion ? `slow motion ×${n.realtime_ratio.toFixed(2)}` : "";
  $("clock").hidden = !n.slow_motion;
}

function frame() {
  try {
    const now = clock.now();
    clock.advance(state.status.dt, (n) => sim.step(n));
    state.status = sim.status();
    readEvents(now);
    if (state.status.grab === "held") state.forces.push([state.status.time, Math.hypot(...state.status.grab_force)]);
    if (now - state.drawnAt >= renderer.drawEveryMs) {
      state.drawnAt = now;
      const drawStart = performance.now();
      draw();
      drawPlot();
      state.drawMs += 0.1 * (performance.now() - drawStart - state.drawMs);
      showWarnings(now);
      showNumbers();
    }
  } catch (e) {
    showError(e);
  }
  requestAnimationFrame(frame);
}

// ---- panel ----
function syncPanel() {
  const s = sim.status();
  state.status = s;
  for (const r of document.querySelectorAll("input[name=solver]")) r.checked = r.value === s.solver;
  for (const r of document.querySelectorAll("input[name=twist]")) {
    r.checked = r.value === s.twist;
    r.disabled = s.solver !== "rod";
  }
  $("effects").replaceChildren(
    ...EFFECTS.map((name) => {
      const label = document.createElement("label");
      const box = document.createElement("input");
      box.type = "checkbox";
      box.checked = s.effects.includes(name);
      const reason = s.unusable[name];
      box.disabled = !!reason;
      box.onchange = () => act(() => sim.setEffect(name, box.checked));
      label.append(box, ` ${name}`);
      if (reason) {
        label.title = reason;
        label.classList.add("unusable");
        const why = document.createElement("div");
        why.className = "reason";
        why.textContent = reason;
        label.append(why);
      }
      return label;
    }),
  );
  const list = $("scene");
  const dropped = list.querySelector("option[data-loaded]");
  if (s.source.startsWith("builtin:")) {
    dropped?.remove();
    list.value = s.scene;
  } else {
    const option = dropped ?? Object.assign(document.createElement("option"), { textContent: "" });
    option.dataset.loaded = "1";
    option.value = `loaded:${s.source}`;
    option.textContent = `${s.source} (${s.scene})`;
    if (!dropped) list.prepend(option);
    list.value = option.value;
  }
}

function act(f, { restart = false, reframe = false } = {}) {
  try {
    f();
    showError("");
    if (reframe) {
      state.followers = sim.followers().slice();
      frameScene();
    }
    if (restart) restartClock();
  } catch (e) {
    showError(e);
  }
  syncPanel();
}

function restartClock() {
  clock.restart();
  state.forces = [];
  state.slips = [];
  state.warnings.clear();
  state.stuckSince = null;
  sim.events();
}

async function loadDefault() {
  const names = sim.builtins();
  $("scene").replaceChildren(
    ...names.map(({ name, about }) => Object.assign(document.createElement("option"), { value: name, textContent: name, title: about })),
  );
  const initial = await fetch("initial.json").then((r) => (r.ok ? r.json() : null)).catch(() => null);
  if (initial?.kind === "hair") {
    const bytes = new Uint8Array(await (await fetch("initial")).arrayBuffer());
    sim.loadHairFile(initial.name, bytes);
  } else if (initial?.kind === "scene") {
    const text = await (await fetch("initial")).text();
    const hair = initial.hair ? new Uint8Array(await (await fetch("initial-hair")).arrayBuffer()) : undefined;
    sim.loadSceneFile(initial.name, text, initial.hair ?? "", hair);
  } else {
    sim.loadBuiltin(initial?.name ?? "firmware");
  }
  state.followers = sim.followers().slice();
}

$("scene").onchange = () => {
  if (!$("scene").value.startsWith("loaded:")) act(() => sim.loadBuiltin($("scene").value), { restart: true, reframe: true });
};
$("pause").onclick = () => setPaused(!clock.paused);
$("step").onclick = () => { setPaused(true); sim.step(1); clock.ran(1); };
$("fit").onclick = () => frameScene();
$("reset").onclick = () => act(() => sim.reset(), { restart: true });
$("stuck-reset").onclick = () => act(() => sim.reset(), { restart: true });
$("followers").onchange = () => { state.withFollowers = $("followers").checked; };
for (const r of document.querySelectorAll("input[name=solver]")) r.onchange = () => act(() => sim.setSolver(r.value), { restart: true });
for (const r of document.querySelectorAll("input[name=twist]")) r.onchange = () => act(() => sim.setTwist(r.value));

function setPaused(paused) {
  clock.paused = paused;
  $("pause").textContent = paused ? "run" : "pause";
}

// ---- pointer: grab, orbit, zoom ----
function nearestNode(x, y) {
  const cam = camera();
  const { points, offsets } = sim.positions();
  let best = null;
  for (let s = 0; s + 1 < offsets.length; s++) {
    for (let n = offsets[s]; n < offsets[s + 1]; n++) {
      const [px, py, z] = cam.project([points[3 * n], points[3 * n + 1], points[3 * n + 2]]);
      const d = Math.hypot(px - x, py - y);
      if (z > 0 && d < GRAB_PIXELS && (!best || d < best.d)) best = { d, strand: s, node: n - offsets[s], z };
    }
  }
  return best;
}

// Grabs the node nearest (x, y); returns whether it did.
function grabAt(x, y) {
  const hit = nearestNode(x, y);
  if (!hit) return false;
  try {
    sim.grab(hit.strand, hit.node);
    state.hand = { depth: hit.z, x, y };
    showError("");
    return true;
  } catch (err) {
    showError(err);
    return false;
  }
}

let orbit = null;
const at = (e) => {
  const r = view.getBoundingClientRect();
  return [e.clientX - r.left, e.clientY - r.top];
};
// Mouse events, not pointer events: a second button pressed during a drag is a `mousedown`
// of its own, and re-grabs a slipped grab without letting go.
view.addEventListener("mousedown", (e) => {
  e.preventDefault();
  const [x, y] = at(e);
  if (state.hand) {
    if (state.status.grab === "slipped") grabAt(state.hand.x, state.hand.y) || grabAt(x, y);
    return;
  }
  if (!e.shiftKey && grabAt(x, y)) return;
  orbit = { x, y };
});
window.addEventListener("mousemove", (e) => {
  const [x, y] = at(e);
  if (state.hand) {
    state.hand.x = x;
    state.hand.y = y;
    sim.moveHand(camera().unproject(x, y, state.hand.depth));
  } else if (orbit) {
    state.camera.yaw -= (x - orbit.x) * 0.01;
    state.camera.pitch = Math.max(-1.5, Math.min(1.5, state.camera.pitch + (y - orbit.y) * 0.01));
    orbit = { x, y };
  }
});
window.addEventListener("mouseup", (e) => {
  if (e.buttons !== 0) return;
  if (state.hand) sim.release();
  state.hand = null;
  orbit = null;
});
window.addEventListener("keydown", (e) => {
  if (e.key === "f") frameScene();
  if (e.key === " " && state.hand && state.status.grab === "slipped") {
    e.preventDefault();
    grabAt(state.hand.x, state.hand.y);
  }
});
view.addEventListener("contextmenu", (e) => e.preventDefault());
view.addEventListener("wheel", (e) => {
  e.preventDefault();
  state.camera.distance *= Math.exp(e.deltaY * 0.001);
}, { passive: false });

// ---- dropped files: a hair file, or a scene file with the hair file it names ----
$("stage").addEventListener("dragover", (e) => e.preventDefault());
$("stage").addEventListener("drop", async (e) => {
  e.preventDefault();
  const files = [...(e.dataTransfer?.files ?? [])];
  if (!files.length) return;
  const read = await Promise.all(files.map(async (f) => ({ name: f.name, bytes: new Uint8Array(await f.arrayBuffer()) })));
  act(() => loadDropped(read), { restart: true, reframe: true });
});

function loadDropped(files) {
  const scene = files.find((f) => f.name.toLowerCase().endsWith(".toml"));
  if (!scene) {
    if (files.length > 1) throw new Error(`${files.map((f) => f.name).join(", ")}: drop one hair file, or a scene .toml with the hair file it names`);
    sim.loadHairFile(files[0].name, files[0].bytes);
  } else {
    const text = new TextDecoder().decode(scene.bytes);
    const others = files.filter((f) => f !== scene);
    const wanted = sim.sceneHairFile(scene.name, text);
    const hair = wanted ? others.find((f) => f.name === wanted) : undefined;
    if (wanted && !hair) {
      throw new Error(`${scene.name}: reads the hair file ${wanted}: drop it together with the scene file` +
        (others.length ? ` (dropped: ${others.map((f) => f.name).join(", ")})` : ""));
    }
    sim.loadSceneFile(scene.name, text, hair?.name ?? "", hair?.bytes);
  }
  state.loaded = files.map((f) => f.name).join(" + ");
}

// ---- what a test drives ----
window.hairsim = {
  status: () => {
    state.status = sim.status();
    return numbers();
  },
  load: (name) => act(() => sim.loadBuiltin(name), { restart: true, reframe: true }),
  pause: (paused = true) => setPaused(paused),
  reset: () => act(() => sim.reset(), { restart: true }),
  restartClock,
  // Moves the page's clock forward by `ms` at once: the next frame sees a stall that long.
  stall: (ms) => clock.skip(ms),
  runSteps: (n) => { sim.step(n); clock.ran(n); return sim.status().state_hash; },
  setSolver: (solver) => act(() => sim.setSolver(solver), { restart: true }),
  setEffect: (name, on) => act(() => sim.setEffect(name, on)),
  error: () => state.error,
  sceneToml: () => sim.sceneToml(),
  // Where node `node` of strand `strand` is, m, and on the screen (x, y in pixels, depth).
  node: (strand, node) => {
    const { points, offsets } = sim.positions();
    const n = offsets[strand] + node;
    return [points[3 * n], points[3 * n + 1], points[3 * n + 2]];
  },
  screen: (strand, node) => camera().project(window.hairsim.node(strand, node)),
  // The stepping cost in µs per step over `steps` steps from the start (the page paused):
  // the median over batches of at least 2 ms each (the page's timer is coarse), after the same
  // steps run once untimed: the browser compiles a module's hot functions a second time,
  // optimised, while the first, quickly compiled code runs.
  benchmark: (steps) => {
    sim.reset();
    const warm = performance.now();
    let warmed = 0;
    // At least 200 ms: the browser optimises a function after it has run a while.
    for (let t = 0; (warmed < steps || t < 200) && t < 1000; t = performance.now() - warm) warmed = sim.step(1);
    // Batches of at least 2 ms at the warm steps' mean cost.
    const batch = Math.max(1, Math.ceil((2 * warmed) / Math.max(1e-3, performance.now() - warm)));
    sim.reset();
    const costs = [];
    for (let done = 0; done < steps; done += batch) {
      const n = Math.min(batch, steps - done);
      const start = performance.now();
      sim.step(n);
      costs.push((1000 * (performance.now() - start)) / n);
    }
    costs.sort((a, b) => a - b);
    sim.reset();
    restartClock();
    return costs[Math.floor(costs.length / 2)] ?? 0;
  },
};

try {
  await loadDefault();
  frameScene();
  syncPanel();
  restartClock();
  window.hairsim.ready = true;
} catch (e) {
  showError(e);
}
requestAnimationFrame(frame);
