// The top-down view: road, cars, planned path and incident markers on a canvas, with a camera
// that follows the ego, zooms about the cursor and pans by dragging.
import { MPH_PER_MPS } from './format.js';

const COLORS = {
  ground: '#1f2a1f',
  road: '#3a3e44',
  edgeLeft: '#e8c547',
  edge: '#f2f2f2',
  laneLine: '#dcdcdc',
  ego: '#3ddc84',
  egoEdge: '#0b3d20',
  car: '#6aa9ff',
  carEdge: '#0d2a4d',
  carHit: '#ff4d4f',
  path: '#ff5ce1',
  incident: '#ff4d4f',
  label: '#f4f6f8',
  labelShadow: 'rgba(0,0,0,0.75)',
};

const MIN_SCALE = 0.05; // px per metre
const MAX_SCALE = 80;
const LABEL_MIN_SCALE = 2.2; // labels only when a car is big enough to read them

/// The view's camera and drawing. `scale` is CSS pixels per metre; `pan` is the offset of the
/// ego from the centre of the view, in CSS pixels.
export class Scene {
  constructor(canvas, replay) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d', { alpha: false });
    this.replay = replay;
    this.scale = 6;
    this.panX = 0;
    this.panY = 0;
    this.headingUp = true;
    this.labels = true;
    this.highlightCars = new Set();
    this.width = 1;
    this.height = 1;
    this.dpr = 1;
    this.rot = 0;
    this._buildRoad();
  }

  setReplay(replay) {
    this.replay = replay;
    this._buildRoad();
  }

  _buildRoad() {
    const lines = this.replay ? this.replay.laneLines : [];
    const toPath = (pts, close) => {
      const p = new Path2D();
      if (pts.length < 4) return p;
      p.moveTo(pts[0], pts[1]);
      for (let i = 2; i + 1 < pts.length; i += 2) p.lineTo(pts[i], pts[i + 1]);
      if (close) p.closePath();
      return p;
    };
    this.linePaths = lines.map((l) => toPath(l, true));
    this.roadPath = null;
    if (lines.length >= 2) {
      const road = new Path2D();
      road.addPath(toPath(lines[0], true));
      road.addPath(toPath(lines[lines.length - 1], true));
      this.roadPath = road;
    }
  }

  /// Sizes the canvas to its box; call on resize.
  resize() {
    const r = this.canvas.getBoundingClientRect();
    this.dpr = window.devicePixelRatio || 1;
    this.width = Math.max(1, r.width);
    this.height = Math.max(1, r.height);
    const w = Math.round(this.width * this.dpr);
    const h = Math.round(this.height * this.dpr);
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
    }
  }

  /// Zooms by `factor` keeping the world point under (sx, sy) (CSS px in the canvas) in place.
  zoomAt(factor, sx, sy) {
    const next = Math.min(MAX_SCALE, Math.max(MIN_SCALE, this.scale * factor));
    const k = next / this.scale;
    const cx = this.width / 2;
    const cy = this.height * this._egoY();
    this.panX = sx - cx - (sx - cx - this.panX) * k;
    this.panY = sy - cy - (sy - cy - this.panY) * k;
    this.scale = next;
  }

  // Where the ego sits, as a fraction of the view's height: lower when heading up, to see ahead.
  _egoY() {
    return this.headingUp ? 0.62 : 0.5;
  }

  recenter() {
    this.panX = 0;
    this.panY = 0;
  }

  // The world-to-screen affine map for the frame: [a, b, c, d, e, f] as in setTransform, in CSS px.
  _transform(ex, ey, yaw) {
    const phi = this.headingUp ? Math.PI / 2 - yaw : 0;
    this.rot = phi;
    const S = this.scale;
    const cos = Math.cos(phi);
    const sin = Math.sin(phi);
    const a = S * cos;
    const b = -S * sin;
    const c = -S * sin;
    const d = -S * cos;
    const e = this.width / 2 + this.panX - (a * ex + c * ey);
    const f = this.height * this._egoY() + this.panY - (b * ex + d * ey);
    return [a, b, c, d, e, f];
  }

  /// Draws frame `i` of the replay.
  draw(i) {
    const ctx = this.ctx;
    const r = this.replay;
    const dpr = this.dpr;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = COLORS.ground;
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    if (!r || r.frames === 0) return;
    const ex = r.egoX[i];
    const ey = r.egoY[i];
    const [a, b, c, d, e, f] = this._transform(ex, ey, r.egoYaw[i]);
    const S = this.scale;
    const px = 1 / S; // one CSS pixel in metres
    ctx.setTransform(a * dpr, b * dpr, c * dpr, d * dpr, e * dpr, f * dpr);

    // road and lane lines
    if (this.roadPath) {
      ctx.fillStyle = COLORS.road;
      ctx.fill(this.roadPath, 'evenodd');
    }
    const n = this.linePaths.length;
    ctx.lineCap = 'butt';
    for (let k = 0; k < n; ++k) {
      const edge = k === 0 || k === n - 1;
      ctx.strokeStyle = k === 0 ? COLORS.edgeLeft : edge ? COLORS.edge : COLORS.laneLine;
      ctx.lineWidth = Math.max(0.15, 1.2 * px);
      ctx.setLineDash(edge ? [] : [3, 9]);
      ctx.stroke(this.linePaths[k]);
    }
    ctx.setLineDash([]);

    // the planned path of the current cycle, from the point the ego has reached
    const pk = r.framePath[i];
    if (pk >= 0) {
      const start = r.pathStart[pk];
      const end = r.pathStart[pk + 1];
      const from = Math.min(end, start + Math.max(0, i - r.pathFrame[pk] - 1));
      if (end - from >= 1) {
        ctx.strokeStyle = COLORS.path;
        ctx.lineWidth = Math.max(0.12, 1.5 * px);
        ctx.beginPath();
        ctx.moveTo(r.pathX[from], r.pathY[from]);
        for (let j = from + 1; j < end; ++j) ctx.lineTo(r.pathX[j], r.pathY[j]);
        ctx.stroke();
        ctx.fillStyle = COLORS.path;
        const dot = Math.max(0.18, 2 * px);
        for (let j = from; j < end; ++j) ctx.fillRect(r.pathX[j] - dot / 2, r.pathY[j] - dot / 2, dot, dot);
      }
    }

    // incidents where they happened: solid once they have, faint before
    const reach = (Math.hypot(this.width, this.height) / 2 + Math.hypot(this.panX, this.panY)) / S + 10;
    const reach2 = reach * reach;
    const mark = Math.max(1.4, 6 * px);
    ctx.lineWidth = Math.max(0.3, 2 * px);
    for (let k = 0; k < r.incidents; ++k) {
      const dx = r.incX[k] - ex;
      const dy = r.incY[k] - ey;
      if (dx * dx + dy * dy > reach2) continue;
      ctx.globalAlpha = r.incFrame[k] <= i ? 1 : 0.3;
      ctx.strokeStyle = COLORS.incident;
      ctx.beginPath();
      ctx.arc(r.incX[k], r.incY[k], mark, 0, Math.PI * 2);
      ctx.moveTo(r.incX[k] - mark * 0.7, r.incY[k] - mark * 0.7);
      ctx.lineTo(r.incX[k] + mark * 0.7, r.incY[k] + mark * 0.7);
      ctx.moveTo(r.incX[k] - mark * 0.7, r.incY[k] + mark * 0.7);
      ctx.lineTo(r.incX[k] + mark * 0.7, r.incY[k] - mark * 0.7);
      ctx.stroke();
    }
    ctx.globalAlpha = 1;

    // cars, then the ego on top
    const L = r.car.length_m || 4.7;
    const W = r.car.width_m || 1.9;
    const c0 = r.carStart[i];
    const c1 = r.carStart[i + 1];
    ctx.lineWidth = Math.max(0.08, 1 * px);
    for (let j = c0; j < c1; ++j) {
      const hit = this.highlightCars.has(r.carId[j]);
      this._car(r.carX[j], r.carY[j], r.carYaw[j], L, W, hit ? COLORS.carHit : COLORS.car, COLORS.carEdge);
    }
    this._car(ex, ey, r.egoYaw[i], L, W, COLORS.ego, COLORS.egoEdge);

    // labels, upright in screen space
    if (this.labels && S >= LABEL_MIN_SCALE) {
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      ctx.font = '11px system-ui, sans-serif';
      ctx.textAlign = 'center';
      ctx.textBaseline = 'bottom';
      const lift = (Math.max(L, W) / 2) * S + 4;
      const label = (x, y, text) => {
        const sx = a * x + c * y + e;
        const sy = b * x + d * y + f - lift;
        ctx.fillStyle = COLORS.labelShadow;
        ctx.fillText(text, sx + 1, sy + 1);
        ctx.fillStyle = COLORS.label;
        ctx.fillText(text, sx, sy);
      };
      for (let j = c0; j < c1; ++j) {
        label(r.carX[j], r.carY[j], `#${r.carId[j]} ${(r.carSpeed[j] * MPH_PER_MPS).toFixed(0)} mph`);
      }
      label(ex, ey, `ego ${(r.egoSpeed[i] * MPH_PER_MPS).toFixed(1)} mph`);
    }
  }

  // One car: an oriented rectangle with a darker windscreen band towards its front.
  _car(x, y, yaw, L, W, fill, edge) {
    const ctx = this.ctx;
    const ux = Math.cos(yaw);
    const uy = Math.sin(yaw);
    const hl = L / 2;
    const hw = W / 2;
    const corner = (s, t) => [x + ux * s - uy * t, y + uy * s + ux * t];
    const p1 = corner(hl, hw);
    const p2 = corner(-hl, hw);
    const p3 = corner(-hl, -hw);
    const p4 = corner(hl, -hw);
    ctx.beginPath();
    ctx.moveTo(p1[0], p1[1]);
    ctx.lineTo(p2[0], p2[1]);
    ctx.lineTo(p3[0], p3[1]);
    ctx.lineTo(p4[0], p4[1]);
    ctx.closePath();
    ctx.fillStyle = fill;
    ctx.fill();
    ctx.strokeStyle = edge;
    ctx.stroke();
    const w1 = corner(hl * 0.45, hw * 0.8);
    const w2 = corner(hl * 0.45, -hw * 0.8);
    const w3 = corner(hl * 0.1, -hw * 0.8);
    const w4 = corner(hl * 0.1, hw * 0.8);
    ctx.beginPath();
    ctx.moveTo(w1[0], w1[1]);
    ctx.lineTo(w2[0], w2[1]);
    ctx.lineTo(w3[0], w3[1]);
    ctx.lineTo(w4[0], w4[1]);
    ctx.closePath();
    ctx.fillStyle = edge;
    ctx.fill();
  }
}
