// The viewer's simulation: loads hairsim_viewer.wasm and wraps its plain C exports
// (std-harness/viewer/src/exports.rs). A call that can fail returns 0, or 1 with the error's
// message in the module's output buffer; here it throws that message.

const encoder = new TextEncoder();
const decoder = new TextDecoder();

// The smallest module that uses a 128-bit SIMD instruction (a function returning
// `i8x16.splat(0)`): a browser that validates it runs the `simd128` build.
const SIMD_PROBE = new Uint8Array([
  0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 8, 1, 6, 0, 65, 0, 253, 15, 11,
]);

export const HAS_SIMD = WebAssembly.validate(SIMD_PROBE);

export class Simulation {
  // The `simd128` build where the browser has it (unless `simd` is false), else the build
  // without SIMD; both give the same bits.
  static async load(simd = HAS_SIMD) {
    const url = simd && HAS_SIMD ? "hairsim_viewer_simd.wasm" : "hairsim_viewer.wasm";
    const { instance } = await WebAssembly.instantiateStreaming(fetch(url), {});
    return new Simulation(instance.exports, url);
  }

  constructor(exports, module) {
    this.x = exports;
    this.module = module;
  }

  // Copies `parts` (strings or byte arrays) into the module's input buffer, one after the
  // other; returns their lengths.
  input(...parts) {
    const bytes = parts.map((p) => (typeof p === "string" ? encoder.encode(p) : p));
    const total = bytes.reduce((n, b) => n + b.length, 0);
    const at = this.x.hs_input(total);
    const memory = new Uint8Array(this.x.memory.buffer, at, total);
    let offset = 0;
    for (const b of bytes) {
      memory.set(b, offset);
      offset += b.length;
    }
    return bytes.map((b) => b.length);
  }

  output() {
    const at = this.x.hs_output_ptr();
    const len = this.x.hs_output_len();
    return decoder.decode(new Uint8Array(this.x.memory.buffer, at, len));
  }

  check(code) {
    if (code !== 0) throw new Error(this.output());
  }

  builtins() {
    this.x.hs_builtins();
    return JSON.parse(this.output());
  }

  loadBuiltin(name) {
    this.check(this.x.hs_load_builtin(...this.input(name)));
  }

  loadHairFile(name, bytes) {
    this.check(this.x.hs_load_hair_file(...this.input(name, bytes)));
  }

  loadSceneFile(name, text, hairName = "", hairBytes = new Uint8Array()) {
    this.check(this.x.hs_load_scene_file(...this.input(name, text, hairName, hairBytes)));
  }

  step(n) {
    return this.x.hs_step(n);
  }

  reset() {
    this.check(this.x.hs_reset());
  }

  // Every node's position (x, y, z) and each strand's first node (strands + 1 entries);
  // views of the module's memory, valid until the next call.
  positions() {
    const nodes = this.x.hs_positions();
    const buffer = this.x.memory.buffer;
    const points = new Float32Array(buffer, this.x.hs_positions_ptr(), 3 * nodes);
    const offsets = new Uint32Array(buffer, this.x.hs_offsets_ptr(), this.x.hs_offsets_len());
    return { points, offsets };
  }

  // The followers: leader index and root offset (head frame, m), four floats each; a view
  // of the module's memory, valid until the next call.
  followers() {
    const count = this.x.hs_followers();
    return new Float32Array(this.x.memory.buffer, this.x.hs_floats_ptr(), 4 * count);
  }

  // One byte of flags per strand (1 rolled back since the last call, 2 stretched past 1 %,
  // 4 held by the hand); a view of the module's memory, valid until the next call.
  strandFlags() {
    const count = this.x.hs_strand_flags();
    return new Uint8Array(this.x.memory.buffer, this.x.hs_bytes_ptr(), count);
  }

  // What the steps since the last call reported (roll-backs, stretch, cap hits, a slip).
  events() {
    this.check(this.x.hs_events());
    return JSON.parse(this.output());
  }

  // The file name of the hair file a scene file reads ("" if none).
  sceneHairFile(name, text) {
    this.check(this.x.hs_scene_hair_file(...this.input(name, text)));
    return this.output();
  }

  // The scene as the page has edited it, as a scene file.
  sceneToml() {
    this.check(this.x.hs_scene_toml());
    return this.output();
  }

  status() {
    this.check(this.x.hs_status());
    return JSON.parse(this.output());
  }

  setSolver(solver) {
    this.check(this.x.hs_set_solver(solver === "rod" ? 1 : 0));
  }

  // `index` in the core's Effect::ALL order (EFFECTS below).
  setEffect(name, on) {
    this.check(this.x.hs_set_effect(EFFECTS.indexOf(name), on ? 1 : 0));
  }

  setTwist(method) {
    this.check(this.x.hs_set_twist(method === "newton" ? 1 : 0));
  }

  grab(strand, node) {
    this.check(this.x.hs_grab(strand, node));
  }

  moveHand([x, y, z]) {
    this.x.hs_move_hand(x, y, z);
  }

  release() {
    this.x.hs_release();
  }
}

// The core's effects, in the order of their bits (hairsim_core::Effect::ALL).
export const EFFECTS = [
  "gravity",
  "drag",
  "bending",
  "twist",
  "inextensibility",
  "collisions",
  "shape",
  "wind",
  "grabs",
  "hair-hair",
];
