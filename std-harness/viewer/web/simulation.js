// The viewer's simulation: loads hairsim_viewer.wasm and wraps its plain C exports
// (std-harness/viewer/src/exports.rs). A call that can fail returns 0, or 1 with the error's
// message in the module's output buffer; here it throws that message.

const encoder = new TextEncoder();
const decoder = new TextDecoder();

export class Simulation {
  static async load(url = "hairsim_viewer.wasm") {
    const response = await fetch(url);
    const { instance } = await WebAssembly.instantiateStreaming(response, {});
    return new Simulation(instance.exports);
  }

  constructor(exports) {
    this.x = exports;
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
