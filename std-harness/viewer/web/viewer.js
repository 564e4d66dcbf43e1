// The page: the simulation in real time at the scene's dt, drawn on a 2-D canvas, the pointer
// as the haptic device. Steps per animation frame are what the elapsed wall time asks; when a
// frame cannot compute them all, the rest carries over (no step is dropped) and the lag shows.

import { Simulation, EFFECTS } from "./simulation.js";

const sim = await Simulation.load();
const $ = (id) => document.getElementById(id);
const view = $("view");
const ctx = view.getContext("2d");

// Largest compute per animation frame, ms: past it the page lags rather than freezes.
const FRAME_BUDGET_MS = 40;

const state = {
  paused: false,
  wallStart: performance.now(),
  wallPaused: 0,
  simulatedSteps: 0,
  computeMs: 0,
  drawMs: 0,
  frames: 0,
  computedSteps: 0,
  status: null,
  camera: { yaw: 0.6, pitch: 0.25, distance: 0.6, centre: [0, 0, 0] },
  hand: null, // { depth, target }
  forces: [], // [wall ms, |F|]
  error: "",
};

function showError(e) {
  state.error = e ? String(e.message ?? e) : "";
  $("error").textContent = state.error;
}

// ---- camera: orbit about the scene's centre, perspective projection ----
function basis() {
  const { yaw, pitch } = state.camera;
  const forward = [-Math.cos(pitch) * Math.sin(yaw), -Math.sin(pitch), -Math.cos(pitch) * Math.cos(yaw)];
  const right = [Math.cos(yaw), 0, -Math.sin(yaw)];
  const up = [
    right[1] * forward[2] - right[2] * forward[1],
    right[2] * forward[0] - right[0] * forward[2],
    right[0] * forward[1] - right[1] * forward[0],
  ];
  const eye = state.camera.centre.map((c, i) => c - forward[i] * state.camera.distance);
  return { forward, right, up, eye };
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

function project(p, b) {
  const d = [p[0] - b.eye[0], p[1] - b.eye[1], p[2] - b.eye[2]];
  const z = dot(d, b.forward);
  const f = view.height / (2 * Math.tan(0.4));
  return [view.width / 2 + (f * dot(d, b.right)) / z, view.height / 2 - (f * dot(d, b.up)) / z, z];
}

// The world point under screen point (sx, sy) at camera depth z.
function unproject(sx, sy, z, b) {
  const f = view.height / (2 * Math.tan(0.4));
  const x = ((sx - view.width / 2) * z) / f;
  const y = (-(sy - view.height / 2) * z) / f;
  return [0, 1, 2].map((i) => b.eye[i] + b.forward[i] * z + b.right[i] * x + b.up[i] * y);
}

function frameScene() {
  const { points } = sim.positions();
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < points.length; i += 3) {
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], points[i + a]);
      hi[a] = Math.max(hi[a], points[i + a]);
    }
  }
  state.camera.centre = lo.map((l, a) => (l + hi[a]) / 2);
  const size = Math.max(...hi.map((h, a) => h - lo[a]), 0.02);
  // The scene fills about two thirds of the view, with room for its motion.
  state.camera.distance = (0.75 * size) / Math.tan(0.4);
}

// ---- drawing ----
function draw() {
  const w = view.clientWidth, h = view.clientHeight;
  if (view.width !== w || view.height !== h) {
    view.width = w;
    view.height = h;
  }
  ctx.fillStyle = "#15171c";
  ctx.fillRect(0, 0, w, h);
  const b = basis();
  const spheres = (state.status?.colliders ?? []).filter((c) => c.sphere).map((c) => c.sphere);
  // Canvas 2D has no depth buffer: hair segments farther than the head's centre are drawn
  // before the head, the others after it.
  const behind = spheres.length ? project(spheres[0].centre, b)[2] : Infinity;
  strokeHair(b, (z) => z > behind);
  for (const sphere of spheres) {
    const [x, y, z] = project(sphere.centre, b);
    if (z <= 0) continue;
    const r = (sphere.radius * view.height) / (2 * Math.tan(0.4) * z);
    ctx.fillStyle = "#3a3f4a";
    ctx.beginPath();
    ctx.arc(x, y, r, 0, 2 * Math.PI);
    ctx.fill();
  }
  strokeHair(b, (z) => z <= behind);
  drawGrab(b);
}

// Strokes every hair segment whose nearer end's depth passes `keep`.
function strokeHair(b, keep) {
  const { points, offsets } = sim.positions();
  ctx.strokeStyle = "#c8914a";
  ctx.lineWidth = 1.2;
  ctx.beginPath();
  for (let s = 0; s + 1 < offsets.length; s++) {
    let previous = null;
    for (let n = offsets[s]; n < offsets[s + 1]; n++) {
      const p = project([points[3 * n], points[3 * n + 1], points[3 * n + 2]], b);
      if (previous && previous[2] > 0 && p[2] > 0 && keep(Math.min(previous[2], p[2]))) {
        ctx.moveTo(previous[0], previous[1]);
        ctx.lineTo(p[0], p[1]);
      }
      previous = p;
    }
  }
  ctx.stroke();
}

function drawGrab(b) {
  const s = state.status;
  if (!s || s.grab !== "held" || !s.grab_target) return;
  const [x, y] = project(s.grab_target, b);
  const f = s.grab_force;
  const magnitude = Math.hypot(...f);
  // The arrow's length grows with the force's logarithm: forces span decades.
  const length = magnitude > 0 ? 20 + 12 * Math.max(0, Math.log10(magnitude / 1e-7)) : 0;
  const tip = project(s.grab_target.map((t, i) => t + (f[i] / (magnitude || 1)) * 1e-3), b);
  const dir = [tip[0] - x, tip[1] - y];
  const dl = Math.hypot(...dir) || 1;
  const end = [x + (dir[0] / dl) * length, y + (dir[1] / dl) * length];
  ctx.strokeStyle = "#6cf";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.arc(x, y, 5, 0, 2 * Math.PI);
  ctx.moveTo(x, y);
  ctx.lineTo(...end);
  ctx.stroke();
}

function drawPlot(now) {
  const plot = $("plot");
  const p = plot.getContext("2d");
  p.fillStyle = "#111";
  p.fillRect(0, 0, plot.width, plot.height);
  state.forces = state.forces.filter(([t]) => now - t <= 2000);
  const top = Math.max(1e-9, ...state.forces.map(([, f]) => f));
  p.strokeStyle = "#6cf";
  p.beginPath();
  state.forces.forEach(([t, f], i) => {
    const x = plot.width * (1 - (now - t) / 2000);
    const y = plot.height * (1 - f / top);
    if (i === 0) p.moveTo(x, y);
    else p.lineTo(x, y);
  });
  p.stroke();
  p.fillStyle = "#aaa";
  p.fillText(`${top.toExponential(2)} N`, 4, 10);
}

// ---- real time ----
function wallSeconds(now) {
  return (now - state.wallStart - state.wallPaused) / 1000;
}

function restartClock() {
  state.wallStart = performance.now();
  state.wallPaused = 0;
  state.simulatedSteps = 0;
  state.computeMs = 0;
  state.drawMs = 0;
  state.frames = 0;
  state.computedSteps = 0;
}

function advance(now) {
  const dt = state.status.dt;
  const due = Math.floor(wallSeconds(now) / dt) - state.simulatedSteps;
  const start = performance.now();
  let done = 0;
  while (done < due && performance.now() - start < FRAME_BUDGET_MS) {
    const batch = Math.min(due - done, 8);
    sim.step(batch);
    done += batch;
  }
  state.computeMs += performance.now() - start;
  state.computedSteps += done;
  state.simulatedSteps += done;
}

function numbers(now) {
  const s = state.status;
  const wall = wallSeconds(now);
  const simulated = state.simulatedSteps * s.dt;
  const usPerSimMs = state.computedSteps ? (1000 * state.computeMs) / (state.computedSteps * s.dt * 1000) : 0;
  return {
    steps: s.steps,
    state_hash: s.state_hash,
    grab_force: s.grab_force,
    us_per_sim_ms: usPerSimMs,
    realtime_ratio: wall > 0 ? simulated / wall : 1,
    lag_s: Math.max(0, wall - simulated),
    steps_per_s: wall > 0 ? state.simulatedSteps / wall : 0,
    frames_per_s: wall > 0 ? state.frames / wall : 0,
    draw_ms_per_frame: state.frames ? state.drawMs / state.frames : 0,
    solver: s.solver,
    effects: s.effects,
    scene: s.scene,
    source: s.source,
    strands: s.strands,
    grab: s.grab,
    grab_target: s.grab_target,
  };
}

let lastFrame = performance.now();
function frame(now) {
  try {
    if (state.paused) state.wallPaused += now - lastFrame;
    else advance(now);
    lastFrame = now;
    state.status = sim.status();
    if (state.status.grab === "held") state.forces.push([now, Math.hypot(...state.status.grab_force)]);
    const drawStart = performance.now();
    draw();
    drawPlot(now);
    state.drawMs += performance.now() - drawStart;
    state.frames += 1;
    const n = numbers(now);
    $("numbers").textContent =
      `time ${(state.status.time).toFixed(3)} s, steps ${n.steps}\n` +
      `${n.us_per_sim_ms.toFixed(0)} µs compute / simulated ms\n` +
      `${n.steps_per_s.toFixed(0)} steps/s\n` +
      `real-time ratio ${n.realtime_ratio.toFixed(3)}, lag ${(1000 * n.lag_s).toFixed(0)} ms\n` +
      `${n.frames_per_s.toFixed(0)} frames/s, ${n.draw_ms_per_frame.toFixed(1)} ms drawing each\n` +
      `${state.status.strands} strands, ${state.status.nodes} nodes\n` +
      `grab ${state.status.grab}\nhash ${n.state_hash}` +
      (state.status.hair_hair_dropped ? "\nhair-hair (SPH) is not simulated here" : "");
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
      box.disabled = !s.supported.includes(name);
      box.onchange = () => act(() => sim.setEffect(name, box.checked));
      label.append(box, ` ${name}`);
      return label;
    }),
  );
}

function act(f, { restart = false } = {}) {
  try {
    f();
    showError("");
  } catch (e) {
    showError(e);
  }
  if (restart) restartClock();
  syncPanel();
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
    const name = initial?.name ?? "firmware";
    sim.loadBuiltin(name);
    $("scene").value = name;
  }
}

$("scene").onchange = () => act(() => { sim.loadBuiltin($("scene").value); frameScene(); }, { restart: true });
$("pause").onclick = () => { state.paused = !state.paused; $("pause").textContent = state.paused ? "run" : "pause"; };
$("step").onclick = () => { state.paused = true; $("pause").textContent = "run"; sim.step(1); state.simulatedSteps += 1; };
$("fit").onclick = () => frameScene();
$("reset").onclick = () => act(() => sim.reset(), { restart: true });
for (const r of document.querySelectorAll("input[name=solver]")) r.onchange = () => act(() => sim.setSolver(r.value), { restart: true });
for (const r of document.querySelectorAll("input[name=twist]")) r.onchange = () => act(() => sim.setTwist(r.value));

// ---- pointer: orbit, zoom, grab ----
function nearestNode(sx, sy) {
  const b = basis();
  const { points, offsets } = sim.positions();
  let best = null;
  for (let s = 0; s + 1 < offsets.length; s++) {
    for (let n = offsets[s]; n < offsets[s + 1]; n++) {
      const [x, y, z] = project([points[3 * n], points[3 * n + 1], points[3 * n + 2]], b);
      const d = Math.hypot(x - sx, y - sy);
      if (z > 0 && d < 12 && (!best || d < best.d)) best = { d, strand: s, node: n - offsets[s], z };
    }
  }
  return best;
}

let orbit = null;
view.addEventListener("pointerdown", (e) => {
  view.setPointerCapture(e.pointerId);
  const hit = nearestNode(e.offsetX, e.offsetY);
  if (hit && !e.shiftKey) {
    try {
      sim.grab(hit.strand, hit.node);
      state.hand = { depth: hit.z };
      showError("");
      return;
    } catch (err) {
      showError(err);
    }
  }
  orbit = { x: e.offsetX, y: e.offsetY };
});
view.addEventListener("pointermove", (e) => {
  if (state.hand) {
    sim.moveHand(unproject(e.offsetX, e.offsetY, state.hand.depth, basis()));
  } else if (orbit) {
    state.camera.yaw -= (e.offsetX - orbit.x) * 0.01;
    state.camera.pitch = Math.max(-1.5, Math.min(1.5, state.camera.pitch + (e.offsetY - orbit.y) * 0.01));
    orbit = { x: e.offsetX, y: e.offsetY };
  }
});
view.addEventListener("pointerup", () => {
  if (state.hand) sim.release();
  state.hand = null;
  orbit = null;
});
view.addEventListener("wheel", (e) => {
  e.preventDefault();
  state.camera.distance *= Math.exp(e.deltaY * 0.001);
}, { passive: false });

// ---- dropped files ----
$("stage").addEventListener("dragover", (e) => e.preventDefault());
$("stage").addEventListener("drop", async (e) => {
  e.preventDefault();
  const file = e.dataTransfer?.files?.[0];
  if (!file) return;
  const bytes = new Uint8Array(await file.arrayBuffer());
  act(() => {
    if (file.name.toLowerCase().endsWith(".toml")) sim.loadSceneFile(file.name, new TextDecoder().decode(bytes));
    else sim.loadHairFile(file.name, bytes);
    frameScene();
  }, { restart: true });
});

// ---- what a test drives ----
window.hairsim = {
  status: () => {
    state.status = sim.status();
    return numbers(performance.now());
  },
  load: (name) => act(() => { sim.loadBuiltin(name); frameScene(); }, { restart: true }),
  pause: (paused = true) => { state.paused = paused; },
  reset: () => act(() => sim.reset(), { restart: true }),
  restartClock,
  runSteps: (n) => { sim.step(n); state.simulatedSteps += n; return sim.status().state_hash; },
  setSolver: (solver) => act(() => sim.setSolver(solver), { restart: true }),
  setEffect: (name, on) => act(() => sim.setEffect(name, on)),
  error: () => state.error,
  screen: (strand, node) => {
    const { points, offsets } = sim.positions();
    const n = offsets[strand] + node;
    return project([points[3 * n], points[3 * n + 1], points[3 * n + 2]], basis());
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
