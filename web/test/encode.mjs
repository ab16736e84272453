// A replay writer for the tests, following docs/replay.md (version 1) to the letter, and a
// synthetic drive on a circular track to feed it.
import { zlibSync } from 'fflate';

const enc = new TextEncoder();

function record(kind, payload) {
  const out = new Uint8Array(5 + payload.length);
  out[0] = kind;
  new DataView(out.buffer).setUint32(1, payload.length, true);
  out.set(payload, 5);
  return out;
}

const cm = (m) => Math.round(m * 100);
const yawUnits = (rad) => {
  let a = rad;
  while (a > Math.PI) a -= 2 * Math.PI;
  while (a < -Math.PI) a += 2 * Math.PI;
  return Math.max(-31415, Math.min(31415, Math.round(a * 1e4)));
};

/// kind 1: one world step.
export function frameRecord(f) {
  const cars = f.cars || [];
  const buf = new Uint8Array(53 + 14 * cars.length);
  const v = new DataView(buf.buffer);
  v.setUint32(0, f.step, true);
  v.setInt32(4, cm(f.x), true);
  v.setInt32(8, cm(f.y), true);
  v.setInt16(12, yawUnits(f.yaw), true);
  v.setUint16(14, Math.round(f.speed * 100), true);
  v.setFloat32(16, f.s, true);
  v.setFloat32(20, f.d, true);
  v.setFloat32(24, f.accT, true);
  v.setFloat32(28, f.accN, true);
  v.setFloat32(32, f.accTotal, true);
  v.setFloat32(36, f.jerk, true);
  v.setFloat32(40, f.distance, true);
  v.setFloat32(44, f.distanceSince, true);
  v.setFloat32(48, f.bestFree, true);
  v.setUint8(52, cars.length);
  let o = 53;
  for (const c of cars) {
    v.setUint16(o, c.id, true);
    v.setInt32(o + 2, cm(c.x), true);
    v.setInt32(o + 6, cm(c.y), true);
    v.setInt16(o + 10, yawUnits(c.yaw), true);
    v.setUint16(o + 12, Math.round(c.speed * 100), true);
    o += 14;
  }
  return record(1, buf);
}

/// kind 2: the path sent at a cycle, [[x, y], ...] in metres.
export function pathRecord(points) {
  const buf = new Uint8Array(2 + 8 * points.length);
  const v = new DataView(buf.buffer);
  v.setUint16(0, points.length, true);
  points.forEach(([x, y], i) => {
    v.setInt32(2 + 8 * i, cm(x), true);
    v.setInt32(6 + 8 * i, cm(y), true);
  });
  return record(2, buf);
}

/// kind 3: an incident at the preceding frame.
export function incidentRecord(inc) {
  const buf = new Uint8Array(18);
  const v = new DataView(buf.buffer);
  v.setUint8(0, inc.type);
  v.setFloat32(1, inc.value, true);
  v.setFloat32(5, inc.s, true);
  v.setUint8(9, inc.lane);
  v.setInt32(10, cm(inc.x), true);
  v.setInt32(14, cm(inc.y), true);
  return record(3, buf);
}

/// kind 4: the run's report.
export function endRecord(report) {
  return record(4, enc.encode(JSON.stringify(report)));
}

export function concat(parts) {
  const n = parts.reduce((a, p) => a + p.length, 0);
  const out = new Uint8Array(n);
  let o = 0;
  for (const p of parts) {
    out.set(p, o);
    o += p.length;
  }
  return out;
}

/// The whole file: magic, version, header, zlib body.
export function encodeReplay(header, records) {
  const head = enc.encode(JSON.stringify(header));
  const pre = new Uint8Array(16);
  pre.set(enc.encode('OVTKRPLY'), 0);
  const v = new DataView(pre.buffer);
  v.setUint32(8, 1, true);
  v.setUint32(12, head.length, true);
  return concat([pre, head, zlibSync(concat(records), { level: 6 })]);
}

const INCIDENT_TYPES = ['collision', 'speeding', 'max_acceleration', 'max_jerk', 'outside_lane'];

/// A drive on a circular track of `trackLength` metres: the ego accelerates in lane 1 among
/// `carCount` cars; `incidents` is a list of {step, type} to record. Returns the file bytes
/// and the frames as plain objects for the assertions.
export function syntheticDrive({ seconds = 20, carCount = 12, incidents = [], trackLength = 6945.554, end = true } = {}) {
  const stepS = 0.02;
  const R = trackLength / (2 * Math.PI);
  const at = (s, d) => {
    const a = s / R;
    const r = R + d; // d to the right of the counter-clockwise reference line is outwards
    return { x: r * Math.cos(a), y: r * Math.sin(a), yaw: a + Math.PI / 2 };
  };
  const laneLines = [0, 4, 8, 12].map((d) => {
    const pts = [];
    for (let s = 0; s < trackLength; s += 5) {
      const p = at(s, d);
      pts.push(Math.round(p.x * 100) / 100, Math.round(p.y * 100) / 100);
    }
    return pts;
  });
  const header = {
    format: 'overtake-replay', version: 1, step_s: stepS,
    road: { lanes: 3, lane_width_m: 4.0 },
    car: { length_m: 4.7, width_m: 1.9 },
    limits: { speed_mps: 22.352, acceleration_mps2: 10.0, jerk_mps3: 10.0 },
    track_length_m: trackLength,
    lane_lines: laneLines,
    incident_types: INCIDENT_TYPES,
    provenance: { policy: 'synthetic', traffic: 'faithful', seed: 1, track: 'circle', duration_s: seconds },
  };
  const records = [];
  const frames = [];
  const steps = Math.round(seconds / stepS);
  let s = 100;
  let v = 0;
  let best = 0;
  let since = 0;
  let dist = 0;
  const incidentAt = new Map(incidents.map((i) => [i.step, i]));
  const recorded = [];
  for (let step = 0; step < steps; ++step) {
    const acc = v < 20 ? 4 : 0;
    v = Math.min(20, v + acc * stepS);
    s += v * stepS;
    dist += v * stepS;
    since += v * stepS;
    best = Math.max(best, since);
    const d = 6;
    const p = at(s, d);
    const cars = [];
    for (let k = 0; k < carCount; ++k) {
      const cs = s + (k - carCount / 2) * 25 + 8;
      const cd = 2 + 4 * (k % 3);
      const cp = at(cs, cd);
      cars.push({ id: k, x: cp.x, y: cp.y, yaw: cp.yaw, speed: 18 + (k % 4) });
    }
    const f = {
      step, x: p.x, y: p.y, yaw: p.yaw, speed: v, s: s % trackLength, d,
      accT: acc, accN: (v * v) / R, accTotal: Math.hypot(acc, (v * v) / R), jerk: step % 50 === 0 ? 3 : 0.5,
      distance: dist, distanceSince: since, bestFree: best, cars,
    };
    frames.push(f);
    records.push(frameRecord(f));
    if (step % 2 === 0) {
      const pts = [];
      for (let j = 1; j <= 50; ++j) {
        const q = at(s + j * Math.max(v, 1) * stepS, d);
        pts.push([q.x, q.y]);
      }
      records.push(pathRecord(pts));
    }
    const inc = incidentAt.get(step);
    if (inc) {
      const type = INCIDENT_TYPES.indexOf(inc.type);
      const rec = { step, type, value: inc.value ?? 1, s: s % trackLength, lane: 1, x: p.x, y: p.y };
      recorded.push(rec);
      records.push(incidentRecord(rec));
      since = 0;
    }
  }
  const report = {
    distance_miles: dist / 1609.344, duration_s: seconds, mean_speed_mph: (dist / seconds) * 2.23694,
    best_incident_free_miles: best / 1609.344, incident_counts: {},
    incidents: recorded.map((r) => ({ type: INCIDENT_TYPES[r.type], t_s: r.step * stepS, s_m: r.s, lane: 1, value: r.value, unit: '' })),
  };
  if (end) records.push(endRecord(report));
  return { bytes: encodeReplay(header, records), header, frames, incidents: recorded, records };
}
