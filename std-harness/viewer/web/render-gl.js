// WebGL2 drawing: hair as camera-facing ribbons shaded with Kajiya–Kay (1989) — diffuse
// from the angle between the strand's tangent and the light, a narrow white highlight and a
// broader one tinted by the hair's colour (the two highlights of Marschner et al. 2003, as
// Scheuermann 2004 approximates them, without the shift) — a root-to-tip colour, a brightness
// per strand, and a depth cue: hair on the side away from the light is darker (a cheap
// stand-in for self-shadowing) and far hair fades toward the background. The followers are
// drawn from their leaders on the GPU (leader positions in a texture, one instance per
// strand). Colliders are shaded meshes: spheres, capsules, and planes as a large tiled disc.

import { PALETTE, strandTint } from "./look.js";

const HAIR_VS = `#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D positions; // leader nodes, xyz
uniform highp usampler2D flags;    // one byte per leader
uniform mat4 viewProjection;
uniform vec4 headRotation;         // quaternion x, y, z, w
uniform vec2 viewport;
uniform float width;               // pixels
uniform float thinnest;            // pixels: without multisampling, thinner ribbons break up
in vec4 strand;                    // first node, nodes, leader, tint
in vec3 offset;                    // follower root offset, head frame
out vec3 tangent;
out vec3 world;
out float along;
out float tint;
flat out uint flag;
const int ROW = 1024;

vec3 node(int i) { return texelFetch(positions, ivec2(i % ROW, i / ROW), 0).xyz; }
vec3 rotate(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }

void main() {
  int first = int(strand.x), count = int(strand.y);
  int k = min(gl_VertexID / 2, count - 1);
  float side = float(gl_VertexID % 2) * 2.0 - 1.0;
  vec3 shift = rotate(headRotation, offset);
  vec3 p = node(first + k) + shift;
  vec3 before = node(first + max(k - 1, 0)) + shift;
  vec3 after = node(first + min(k + 1, count - 1)) + shift;
  tangent = normalize(after - before + vec3(1e-9));
  world = p;
  along = float(k) / float(max(count - 1, 1));
  tint = strand.w;
  int leader = int(strand.z);
  flag = texelFetch(flags, ivec2(leader % ROW, leader / ROW), 0).r;
  vec4 a = viewProjection * vec4(before, 1.0);
  vec4 b = viewProjection * vec4(after, 1.0);
  vec4 c = viewProjection * vec4(p, 1.0);
  vec2 direction = (b.xy / b.w - a.xy / a.w) * viewport;
  vec2 normal = length(direction) > 1e-6 ? normalize(vec2(-direction.y, direction.x)) : vec2(1.0, 0.0);
  // Thinner toward the tip, as hair tapers.
  float w = max(width * (1.0 - 0.5 * along), thinnest) + (flag != 0u ? 1.0 : 0.0);
  c.xy += normal * side * w / viewport * c.w;
  gl_Position = c;
}`;

const HAIR_FS = `#version 300 es
precision highp float;
uniform vec3 eye;
uniform vec3 light;
uniform vec3 rootColour;
uniform vec3 tipColour;
uniform vec3 background;
uniform vec3 warning;
uniform vec3 held;
uniform vec4 volume;   // centre, radius of the hair
uniform float fogNear;
uniform float fogFar;
in vec3 tangent;
in vec3 world;
in float along;
in float tint;
flat in uint flag;
out vec4 colour;

void main() {
  vec3 t = normalize(tangent);
  vec3 v = normalize(eye - world);
  vec3 h = normalize(light + v);
  float tl = dot(t, light), th = dot(t, h);
  float diffuse = sqrt(max(0.0, 1.0 - tl * tl));
  float sinTH = sqrt(max(0.0, 1.0 - th * th));
  vec3 base = mix(rootColour, tipColour, along) * tint;
  if ((flag & 3u) != 0u) base = warning;
  else if ((flag & 4u) != 0u) base = mix(base, held, 0.6);
  // Self-shadowing stand-in: the hair's far side from the light gets less of it.
  float depth = clamp(0.5 - 0.5 * dot(world - volume.xyz, light) / volume.w, 0.0, 1.0);
  float shadow = mix(1.0, 0.35, depth);
  vec3 lit = base * (0.25 + 0.75 * diffuse * shadow)
    + vec3(0.30) * pow(sinTH, 90.0) * shadow
    + base * 0.45 * pow(sinTH, 18.0) * shadow;
  float fog = clamp((distance(world, eye) - fogNear) / max(fogFar - fogNear, 1e-6), 0.0, 1.0);
  colour = vec4(mix(lit, background, 0.55 * fog), 1.0);
}`;

const SOLID_VS = `#version 300 es
precision highp float;
uniform mat4 viewProjection;
uniform vec3 a;        // sphere centre, capsule end, or plane centre
uniform vec3 b;        // capsule's other end
uniform vec3 axisU;    // the solid's frame: axisW along the capsule or the plane's normal
uniform vec3 axisV;
uniform vec3 axisW;
uniform float radius;
in vec3 direction;     // unit direction from the centre, in the solid's frame
in float end;          // 0 at a, 1 at b
out vec3 normal;
out vec3 world;
void main() {
  vec3 d = direction.x * axisU + direction.y * axisV + direction.z * axisW;
  world = mix(a, b, end) + radius * d;
  normal = d;
  gl_Position = viewProjection * vec4(world, 1.0);
}`;

const SOLID_FS = `#version 300 es
precision highp float;
uniform vec3 eye;
uniform vec3 light;
uniform vec3 fill;
uniform float plane;   // 1 for a plane: tiles, and fades out at its rim
uniform vec3 a;
uniform vec3 axisU;
uniform vec3 axisV;
uniform float radius;
in vec3 normal;
in vec3 world;
out vec4 colour;
void main() {
  vec3 n = normalize(normal);
  vec3 v = normalize(eye - world);
  if (plane > 0.5 && dot(n, v) < 0.0) n = -n;
  float lambert = max(0.0, dot(n, light));
  float sky = 0.5 + 0.5 * n.y;
  float rim = pow(1.0 - max(0.0, dot(n, v)), 3.0);
  vec3 c = fill * (0.22 + 0.18 * sky + 0.6 * lambert) + vec3(0.10) * rim;
  float alpha = 1.0;
  if (plane > 0.5) {
    vec2 q = vec2(dot(world - a, axisU), dot(world - a, axisV)) / (0.08 * radius);
    float tile = mod(floor(q.x) + floor(q.y), 2.0);
    c *= 0.9 + 0.1 * tile;
    alpha = 1.0 - smoothstep(0.6, 1.0, length(world - a) / radius);
  }
  colour = vec4(c, alpha);
}`;

function compile(gl, vs, fs) {
  const program = gl.createProgram();
  for (const [kind, source] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
    const shader = gl.createShader(kind);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(`shader: ${gl.getShaderInfoLog(shader)}`);
    gl.attachShader(program, shader);
  }
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`shader: ${gl.getProgramInfoLog(program)}`);
  const uniforms = {};
  for (let i = 0; i < gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS); i++) {
    const { name } = gl.getActiveUniform(program, i);
    uniforms[name] = gl.getUniformLocation(program, name);
  }
  return { program, uniforms };
}

// A unit sphere as latitude rings from the −z pole to the +z pole, each vertex tagged with
// the capsule end it belongs to (the equator ring twice, once per end: the cylinder between).
function sphereMesh(rings = 16, sectors = 32) {
  const direction = [];
  const end = [];
  const rows = [];
  for (let r = 0; r <= rings; r++) {
    const latitude = -Math.PI / 2 + (Math.PI * r) / rings;
    const copies = r === rings / 2 ? [0, 1] : [latitude < 0 ? 0 : 1];
    for (const e of copies) {
      rows.push(direction.length / 3);
      for (let s = 0; s <= sectors; s++) {
        const longitude = (2 * Math.PI * s) / sectors;
        direction.push(Math.cos(latitude) * Math.cos(longitude), Math.cos(latitude) * Math.sin(longitude), Math.sin(latitude));
        end.push(e);
      }
    }
  }
  const index = [];
  for (let r = 0; r + 1 < rows.length; r++) {
    for (let s = 0; s < sectors; s++) {
      const i = rows[r] + s, j = rows[r + 1] + s;
      index.push(i, j, i + 1, i + 1, j, j + 1);
    }
  }
  return { direction: new Float32Array(direction), end: new Float32Array(end), index: new Uint16Array(index) };
}

// A flat disc in the solid's uv plane (z = 0), as a fan of rings.
function discMesh(rings = 12, sectors = 48) {
  const direction = [0, 0, 0];
  const index = [];
  for (let r = 1; r <= rings; r++) {
    for (let s = 0; s < sectors; s++) {
      const angle = (2 * Math.PI * s) / sectors;
      direction.push((r / rings) * Math.cos(angle), (r / rings) * Math.sin(angle), 0);
    }
  }
  const at = (r, s) => (r === 0 ? 0 : 1 + (r - 1) * sectors + (s % sectors));
  for (let r = 0; r < rings; r++) {
    for (let s = 0; s < sectors; s++) {
      if (r === 0) index.push(0, at(1, s), at(1, s + 1));
      else index.push(at(r, s), at(r + 1, s), at(r, s + 1), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
    }
  }
  return { direction: new Float32Array(direction), end: new Float32Array(direction.length / 3), index: new Uint16Array(index) };
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => {
  const l = Math.hypot(...a) || 1;
  return a.map((x) => x / l);
};
// Two unit vectors perpendicular to unit `w` and to each other.
function frameAround(w) {
  const u = unit(cross(Math.abs(w[1]) < 0.9 ? [0, 1, 0] : [1, 0, 0], w));
  return [u, cross(w, u)];
}
const rgb = (c) => c.map((x) => x / 255);

// The name of the WebGL2 renderer, from a throwaway context ("" where it is hidden).
function rendererName() {
  const gl = document.createElement("canvas").getContext("webgl2");
  if (!gl) return "";
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
  gl.getExtension("WEBGL_lose_context")?.loseContext();
  return String(name);
}

export class GlRenderer {
  // Throws where WebGL2 (or a float texture) is missing: the page falls back to Canvas 2D.
  constructor(canvas) {
    // Multisampling where a GPU draws; not on a software rasteriser (SwiftShader, as headless
    // Chromium has), where it costs several times the frame.
    const software = /SwiftShader|llvmpipe|software/i.test(rendererName());
    const gl = canvas.getContext("webgl2", { antialias: !software, alpha: false, preserveDrawingBuffer: true });
    if (!gl) throw new Error("no WebGL2");
    this.gl = gl;
    this.canvas = canvas;
    this.kind = `WebGL2${software ? " (software)" : ""}`;
    this.software = software;
    // A software rasteriser takes the cores the simulation steps on: it draws less often.
    this.drawEveryMs = software ? 150 : 0;
    this.hair = compile(gl, HAIR_VS, HAIR_FS);
    this.solid = compile(gl, SOLID_VS, SOLID_FS);
    this.positions = gl.createTexture();
    this.flags = gl.createTexture();
    this.instances = gl.createBuffer();
    this.hairVao = gl.createVertexArray();
    gl.bindVertexArray(this.hairVao);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.instances);
    const strandAt = gl.getAttribLocation(this.hair.program, "strand");
    const offsetAt = gl.getAttribLocation(this.hair.program, "offset");
    gl.enableVertexAttribArray(strandAt);
    gl.vertexAttribPointer(strandAt, 4, gl.FLOAT, false, 28, 0);
    gl.vertexAttribDivisor(strandAt, 1);
    gl.enableVertexAttribArray(offsetAt);
    gl.vertexAttribPointer(offsetAt, 3, gl.FLOAT, false, 28, 16);
    gl.vertexAttribDivisor(offsetAt, 1);
    gl.bindVertexArray(null);
    this.meshes = { sphere: this.mesh(sphereMesh()), disc: this.mesh(discMesh()) };
    this.instanceKey = null;
  }

  mesh({ direction, end, index }) {
    const gl = this.gl;
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    for (const [name, data, size] of [["direction", direction, 3], ["end", end, 1]]) {
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
      const at = gl.getAttribLocation(this.solid.program, name);
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, size, gl.FLOAT, false, 0, 0);
    }
    const indices = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, indices);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, index, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    return { vao, count: index.length };
  }

  // One instance per drawn strand: the leaders, then (if `withFollowers`) the followers.
  setInstances(offsets, followers, withFollowers) {
    const key = `${offsets.length}:${offsets[offsets.length - 1]}:${followers.length}:${withFollowers}`;
    if (key === this.instanceKey) return;
    this.instanceKey = key;
    const leaders = offsets.length - 1;
    const count = leaders + (withFollowers ? followers.length / 4 : 0);
    const data = new Float32Array(7 * count);
    let maxNodes = 1;
    const put = (i, leader, offset) => {
      const nodes = offsets[leader + 1] - offsets[leader];
      maxNodes = Math.max(maxNodes, nodes);
      data.set([offsets[leader], nodes, leader, strandTint(i), ...offset], 7 * i);
    };
    for (let s = 0; s < leaders; s++) put(s, s, [0, 0, 0]);
    if (withFollowers) {
      for (let f = 0; f < followers.length / 4; f++) {
        put(leaders + f, followers[4 * f], [followers[4 * f + 1], followers[4 * f + 2], followers[4 * f + 3]]);
      }
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.instances);
    gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
    this.instanceCount = count;
    this.maxNodes = maxNodes;
  }

  upload(texture, format, internal, type, data, items, channels) {
    const gl = this.gl;
    const row = 1024;
    const height = Math.max(1, Math.ceil(items / row));
    const padded = new data.constructor(row * height * channels);
    padded.set(data.subarray(0, items * channels));
    gl.bindTexture(gl.TEXTURE_2D, texture);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texImage2D(gl.TEXTURE_2D, 0, internal, row, height, 0, format, type, padded);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  }

  // `frame`: { camera (viewProjection, eye, width, height), points, offsets, followers,
  // withFollowers, flags, head rotation, colliders, volume [centre, radius], strandWidth }.
  draw(frame) {
    const gl = this.gl;
    const { camera } = frame;
    gl.viewport(0, 0, camera.width, camera.height);
    gl.clearColor(...rgb(PALETTE.background), 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    const light = unit(PALETTE.light);
    this.drawSolids(frame, light);
    this.drawHair(frame, light);
  }

  drawHair(frame, light) {
    const gl = this.gl;
    const { camera, points, offsets, flags } = frame;
    const nodes = points.length / 3;
    if (nodes === 0) return;
    this.setInstances(offsets, frame.followers, frame.withFollowers);
    gl.activeTexture(gl.TEXTURE0);
    this.upload(this.positions, gl.RGB, gl.RGB32F, gl.FLOAT, points, nodes, 3);
    gl.activeTexture(gl.TEXTURE1);
    this.upload(this.flags, gl.RED_INTEGER, gl.R8UI, gl.UNSIGNED_BYTE, flags, flags.length, 1);
    const { program, uniforms: u } = this.hair;
    gl.useProgram(program);
    gl.uniform1i(u.positions, 0);
    gl.uniform1i(u.flags, 1);
    gl.uniformMatrix4fv(u.viewProjection, false, camera.viewProjection);
    gl.uniform4fv(u.headRotation, frame.headRotation);
    gl.uniform2f(u.viewport, camera.width / 2, camera.height / 2);
    gl.uniform1f(u.width, frame.strandWidth / 2);
    gl.uniform1f(u.thinnest, this.software ? 0.75 : 0.3);
    gl.uniform3fv(u.eye, camera.eye);
    gl.uniform3fv(u.light, light);
    gl.uniform3fv(u.rootColour, rgb(PALETTE.root));
    gl.uniform3fv(u.tipColour, rgb(PALETTE.tip));
    gl.uniform3fv(u.background, rgb(PALETTE.background));
    gl.uniform3fv(u.warning, rgb(PALETTE.warning));
    gl.uniform3fv(u.held, rgb(PALETTE.held));
    gl.uniform4f(u.volume, ...frame.volume[0], frame.volume[1]);
    const distance = Math.hypot(...sub(frame.volume[0], camera.eye));
    gl.uniform1f(u.fogNear, distance - frame.volume[1]);
    gl.uniform1f(u.fogFar, distance + frame.volume[1]);
    gl.bindVertexArray(this.hairVao);
    gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 2 * this.maxNodes, this.instanceCount);
    gl.bindVertexArray(null);
  }

  drawSolids(frame, light) {
    const gl = this.gl;
    const { program, uniforms: u } = this.solid;
    gl.useProgram(program);
    gl.uniformMatrix4fv(u.viewProjection, false, frame.camera.viewProjection);
    gl.uniform3fv(u.eye, frame.camera.eye);
    gl.uniform3fv(u.light, light);
    gl.uniform3fv(u.fill, rgb(PALETTE.collider));
    const solid = (mesh, a, b, w, radius, plane) => {
      const [uAxis, vAxis] = frameAround(w);
      gl.uniform3fv(u.a, a);
      gl.uniform3fv(u.b, b);
      gl.uniform3fv(u.axisU, uAxis);
      gl.uniform3fv(u.axisV, vAxis);
      gl.uniform3fv(u.axisW, w);
      gl.uniform1f(u.radius, radius);
      gl.uniform1f(u.plane, plane ? 1 : 0);
      gl.bindVertexArray(mesh.vao);
      gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_SHORT, 0);
    };
    for (const c of frame.colliders) {
      if (c.sphere) solid(this.meshes.sphere, c.sphere.centre, c.sphere.centre, [0, 0, 1], c.sphere.radius, false);
      if (c.capsule) {
        const { a, b, radius } = c.capsule;
        const axis = sub(b, a);
        solid(this.meshes.sphere, a, b, Math.hypot(...axis) > 0 ? unit(axis) : [0, 0, 1], radius, false);
      }
    }
    // Planes last, blended: their rim fades out.
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    gl.depthMask(false);
    for (const c of frame.colliders) {
      if (!c.plane) continue;
      const n = unit(c.plane.normal);
      // The disc's centre: the hair's centre dropped onto the plane.
      const [centre, size] = frame.volume;
      const height = n.reduce((s, x, i) => s + x * (centre[i] - c.plane.point[i]), 0);
      const foot = centre.map((x, i) => x - height * n[i]);
      solid(this.meshes.disc, foot, foot, n, 4 * size, true);
    }
    gl.depthMask(true);
    gl.disable(gl.BLEND);
    gl.bindVertexArray(null);
  }
}
