// Canvas 2D drawing, where WebGL2 is missing: the same strands (followers included), the
// root-to-tip colour and the diffuse term of the WebGL shading in a few steps, colliders as
// shaded discs and stadiums, painted far to near around the first sphere (no depth buffer).

import { PALETTE } from "./look.js";

const SHADES = 6;
const css = (c, k = 1) => `rgb(${c.map((x) => Math.round(Math.min(255, x * k))).join(",")})`;

function rotate(q, v) {
  // v + 2 q × (q × v + w v)
  const [x, y, z, w] = q;
  const t = [y * v[2] - z * v[1] + w * v[0], z * v[0] - x * v[2] + w * v[1], x * v[1] - y * v[0] + w * v[2]];
  return [v[0] + 2 * (y * t[2] - z * t[1]), v[1] + 2 * (z * t[0] - x * t[2]), v[2] + 2 * (x * t[1] - y * t[0])];
}

export class CanvasRenderer {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.kind = "Canvas 2D";
    this.drawEveryMs = 0;
  }

  draw(frame) {
    const { ctx } = this;
    const { camera } = frame;
    ctx.fillStyle = css(PALETTE.background);
    ctx.fillRect(0, 0, camera.width, camera.height);
    const spheres = frame.colliders.filter((c) => c.sphere).map((c) => c.sphere);
    const behind = spheres.length ? camera.project(spheres[0].centre)[2] : Infinity;
    const segments = this.segments(frame);
    this.stroke(segments.filter((s) => s.z > behind), frame);
    for (const c of frame.colliders) {
      if (c.sphere) this.disc(camera, c.sphere.centre, c.sphere.radius);
      if (c.capsule) this.stadium(camera, c.capsule);
    }
    this.stroke(segments.filter((s) => s.z <= behind), frame);
  }

  // Every drawn segment, projected, with its colour bucket.
  segments(frame) {
    const { camera, points, offsets, followers, withFollowers, flags, headRotation } = frame;
    const light = PALETTE.light.map((x) => x / Math.hypot(...PALETTE.light));
    const out = [];
    const strand = (leader, shift) => {
      const first = offsets[leader], count = offsets[leader + 1] - first;
      let previous = null;
      for (let k = 0; k < count; k++) {
        const i = 3 * (first + k);
        const p = [points[i] + shift[0], points[i + 1] + shift[1], points[i + 2] + shift[2]];
        const q = camera.project(p);
        if (previous && previous.q[2] > 0 && q[2] > 0) {
          const t = [p[0] - previous.p[0], p[1] - previous.p[1], p[2] - previous.p[2]];
          const tl = (t[0] * light[0] + t[1] * light[1] + t[2] * light[2]) / (Math.hypot(...t) || 1);
          const diffuse = Math.sqrt(Math.max(0, 1 - tl * tl));
          out.push({
            a: previous.q, b: q, z: Math.min(previous.q[2], q[2]),
            warn: flags[leader] & 3,
            along: Math.min(SHADES - 1, Math.floor((SHADES * k) / count)),
            shade: Math.min(SHADES - 1, Math.floor(SHADES * diffuse)),
          });
        }
        previous = { p, q };
      }
    };
    for (let s = 0; s + 1 < offsets.length; s++) strand(s, [0, 0, 0]);
    if (withFollowers) {
      for (let f = 0; f < followers.length; f += 4) {
        strand(followers[f], rotate(headRotation, [followers[f + 1], followers[f + 2], followers[f + 3]]));
      }
    }
    return out;
  }

  // One path per colour bucket.
  stroke(segments, frame) {
    const { ctx } = this;
    const buckets = new Map();
    for (const s of segments) {
      const key = s.warn ? "warn" : `${s.along}:${s.shade}`;
      if (!buckets.has(key)) buckets.set(key, []);
      buckets.get(key).push(s);
    }
    ctx.lineWidth = frame.strandWidth;
    ctx.lineCap = "round";
    for (const [key, list] of buckets) {
      if (key === "warn") ctx.strokeStyle = css(PALETTE.warning);
      else {
        const [along, shade] = key.split(":").map(Number);
        const t = (along + 0.5) / SHADES;
        const base = PALETTE.root.map((r, i) => r + (PALETTE.tip[i] - r) * t);
        ctx.strokeStyle = css(base, 0.3 + (0.9 * (shade + 0.5)) / SHADES);
      }
      ctx.beginPath();
      for (const { a, b } of list) {
        ctx.moveTo(a[0], a[1]);
        ctx.lineTo(b[0], b[1]);
      }
      ctx.stroke();
    }
  }

  disc(camera, centre, radius) {
    const [x, y, z] = camera.project(centre);
    if (z <= 0) return;
    const r = camera.pixels(radius, z);
    const g = this.ctx.createRadialGradient(x - 0.35 * r, y - 0.45 * r, 0.1 * r, x, y, r);
    g.addColorStop(0, css(PALETTE.collider, 0.95));
    g.addColorStop(1, css(PALETTE.collider, 0.3));
    this.ctx.fillStyle = g;
    this.ctx.beginPath();
    this.ctx.arc(x, y, r, 0, 2 * Math.PI);
    this.ctx.fill();
  }

  stadium(camera, { a, b, radius }) {
    const pa = camera.project(a), pb = camera.project(b);
    if (pa[2] <= 0 || pb[2] <= 0) return;
    const { ctx } = this;
    ctx.strokeStyle = css(PALETTE.collider, 0.55);
    ctx.lineCap = "round";
    ctx.lineWidth = 2 * camera.pixels(radius, (pa[2] + pb[2]) / 2);
    ctx.beginPath();
    ctx.moveTo(pa[0], pa[1]);
    ctx.lineTo(pb[0] + 1e-3, pb[1]);
    ctx.stroke();
  }
}
