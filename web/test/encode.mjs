// A replay writer for the tests, following docs/replay.md (version 2) to the letter, and a
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

/// The stored fixed point (docs/replay.md): cm, 1e-4 rad, cm/s, rounded and clamped.
export const cm = (m) => Math.max(-2147483648, Math.min(2147483647, Math.round(m * 100)));
export const yawUnits = (rad) => {
  let a = rad;
  while (a > Math.PI) a -= 2 * Math.PI;
  while (a < -Math.PI) a += 2 * Math.PI;
  return Math.max(-31415, Math.min(31415, Math.round(a * 1e4)));
};
export const speedUnits = (mps) => Math.max(0, Math.min(65535, Math.round(mps * 100)));
/// A TTC or headway in 0.01 s: 65535 for none (null, Infinity) and from 655.35 s on.
export const centiseconds = (s) => (s == null || !(s < 655.35) ? 65535 : Math.max(0, Math.min(65534, Math.round(s * 100))));

// A growing payload: little-endian fields and LEB128 varints.
class Bytes {
  constructor() {
    this.a = [];
  }
  u8(v) {
    this.a.push(v & 0xff);
  }
  u16(v) {
    this.a.push(v & 0xff, (v >> 8) & 0xff);
  }
  u32(v) {
    for (let i = 0; i < 4; ++i) this.a.push(Math.floor(v / 2 ** (8 * i)) & 0xff);
  }
  f32(v) {
    const b = new Uint8Array(4);
    new DataView(b.buffer).setFloat32(0, v, true);
    this.a.push(...b);
  }
  uvarint(v) {
    while (v >= 0x80) {
      this.a.push((v % 0x80) | 0x80);
      v = Math.floor(v / 0x80);
    }
    this.a.push(v);
  }
  /// A signed difference: zigzag (0, -1, 1, -2 ... -> 0, 1, 2, 3 ...), then LEB128.
  delta(d) {
    this.uvarint(d >= 0 ? 2 * d : -2 * d - 1);
  }
  bytes() {
    return Uint8Array.from(this.a);
  }
}

/// Writes the records of one run: frames and paths are coded against the frame before, so
/// one writer sees the run from its first frame.
export class RecordWriter {
  constructor() {
    this.ego = [0, 0, 0, 0]; // the last frame's ego: x, y (cm), yaw (1e-4 rad), speed (cm/s)
    this.cars = new Map(); // the last frame's cars: id -> [x, y, yaw, speed]
  }

  /// kind 1: one world step. `f.cars` holds {id, x, y, yaw, speed} with unique ids;
  /// `f.safety` {ttcAhead, ttcEntering, headway} in seconds (null or Infinity: none) adds the
  /// fields added within version 2 (without it, the frame is an older writer's).
  frame(f) {
    const b = new Bytes();
    b.u32(f.step);
    const ego = [cm(f.x), cm(f.y), yawUnits(f.yaw), speedUnits(f.speed)];
    ego.forEach((v, i) => b.delta(v - this.ego[i]));
    this.ego = ego;
    for (const k of ['s', 'd', 'accT', 'accN', 'accTotal', 'jerk', 'distance', 'distanceSince', 'bestFree']) b.f32(f[k]);
    const cars = f.cars || [];
    b.u8(cars.length);
    const now = cars.map((c) => [cm(c.x), cm(c.y), yawUnits(c.yaw), speedUnits(c.speed)]);
    for (const c of cars) b.uvarint(c.id);
    for (let j = 0; j < 4; ++j) {
      cars.forEach((c, k) => b.delta(now[k][j] - (this.cars.has(c.id) ? this.cars.get(c.id)[j] : 0)));
    }
    this.cars = new Map(cars.map((c, k) => [c.id, now[k]]));
    if (f.safety) for (const k of ['ttcAhead', 'ttcEntering', 'headway']) b.u16(centiseconds(f.safety[k]));
    return record(1, b.bytes());
  }

  /// kind 2: the path sent at a cycle, [[x, y], ...] in metres; the first point from the
  /// ego of the last frame, the others from the point before.
  path(points) {
    const b = new Bytes();
    b.u16(points.length);
    let [x, y] = this.ego;
    for (const [px, py] of points) {
      b.delta(cm(px) - x);
      b.delta(cm(py) - y);
      [x, y] = [cm(px), cm(py)];
    }
    return record(2, b.bytes());
  }
}

/// kind 3: an incident at the preceding frame. With `inc.kind` (an index into the header's
/// collision_kinds, or 255 for none) and `inc.atFault`, the 20-byte record of version 2's
/// later writers; without, an older writer's 18 bytes. With `inc.contact` too (the collision's
/// contact from 0, or -1 / null for none), the 24-byte record of the writers that count
/// contacts: a u32 contact number from 1 (0 for none).
export function incidentRecord(inc) {
  const classified = inc.kind !== undefined;
  const counted = classified && inc.contact !== undefined;
  const buf = new Uint8Array(counted ? 24 : classified ? 20 : 18);
  const v = new DataView(buf.buffer);
  v.setUint8(0, inc.type);
  v.setFloat32(1, inc.value, true);
  v.setFloat32(5, inc.s, true);
  v.setUint8(9, inc.lane);
  v.setInt32(10, cm(inc.x), true);
  v.setInt32(14, cm(inc.y), true);
  if (classified) {
    v.setUint8(18, inc.kind);
    v.setUint8(19, inc.atFault ? 1 : 0);
  }
  if (counted) v.setUint32(20, inc.contact === null || inc.contact < 0 ? 0 : inc.contact + 1, true);
  return record(3, buf);
}

/// kind 4: the run's report.
export function endRecord(report) {
  return record(4, enc.encode(JSON.stringify(report)));
}

/// kind 5: a checkpoint, the world's state in binary (for `overtake cut`; the page skips it).
/// The payload here is `n` bytes of a pattern that holds bytes like record heads (1 to 5) and
/// varints' continuation bits, so a reader that looked inside would stumble.
export function checkpointRecord(n = 300) {
  const payload = new Uint8Array(n);
  for (let i = 0; i < n; ++i) payload[i] = i % 7 === 0 ? 1 + (i % 5) : (i * 37 + 0x80) & 0xff;
  return record(5, payload);
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
export function encodeReplay(header, records, version = 2) {
  const head = enc.encode(JSON.stringify(header));
  const pre = new Uint8Array(16);
  pre.set(enc.encode('OVTKRPLY'), 0);
  const v = new DataView(pre.buffer);
  v.setUint32(8, version, true);
  v.setUint32(12, head.length, true);
  return concat([pre, head, zlibSync(concat(records), { level: 6 })]);
}

const INCIDENT_TYPES = ['collision', 'speeding', 'max_acceleration', 'max_jerk', 'outside_lane'];
export const COLLISION_KINDS = ['ego_hit_car_ahead', 'hit_from_behind', 'hit_from_behind_braking', 'ego_lane_change',
  'car_cut_in', 'side_contact', 'ego_stopped', 'car_stopped'];

/// The synthetic drive's TTC and headway at a step (seconds; Infinity for none): a car ahead
/// that closes in and falls back, a lane change now and then, and stretches with nobody ahead.
export function syntheticSafety(step) {
  const phase = step % 500;
  const ahead = phase < 350;
  return {
    ttcAhead: ahead && phase > 50 ? 0.8 + (phase - 50) * 0.013 : Infinity,
    ttcEntering: step % 700 > 600 ? 2.5 - (step % 700 - 600) * 0.02 : Infinity,
    headway: ahead ? 0.6 + phase * 0.00437 : Infinity,
  };
}

/// A drive on a circular track of `trackLength` metres: the ego accelerates in lane 1 among
/// `carCount` cars; `incidents` is a list of {step, type} to record. With `churn`, the cars
/// come and go: each leaves for 6 steps in every 90, the order of the list flips every 37
/// steps, and a car with the id 65535 jumps between two far ends of the i32 range (5-byte
/// differences). `legacy` writes as a writer from before TTC, headway and collision classes
/// (no collision_kinds, frames without their last six bytes, 18-byte incidents); otherwise an
/// incident may give `kind` (a collision kind's name) and `atFault`. Collisions are counted as
/// contacts, one per car (an incident's `value`) touched: a collision with the car of the
/// collision before it (within `contactGapSteps`) repeats that contact, as the rubric's latched
/// incident of every second of contact does; `preContacts` writes as a writer from before
/// contacts (20-byte incidents, a report whose collisions have no `contacts` and count every
/// incident). As the replay of a cut
/// scenario: `startStep`, the step of the first frame (the run's clock: a cut starts later
/// than 0; an incident's step is one of the frames'), and `cutFrom`, the header's
/// provenance.cut_from. `checkpointEvery` adds a checkpoint record (kind 5) after the first
/// frame and every so many frames after it, as the C++ writer does. Returns the file bytes and
/// the frames as plain objects for the assertions.
export function syntheticDrive({
  seconds = 20, carCount = 12, incidents = [], trackLength = 6945.554, end = true, churn = false, legacy = false,
  startStep = 0, cutFrom = null, checkpointEvery = 0, preContacts = false, contactGapSteps = 60,
} = {}) {
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
    format: 'overtake-replay', version: 2, step_s: stepS,
    road: { lanes: 3, lane_width_m: 4.0 },
    car: { length_m: 4.7, width_m: 1.9 },
    limits: { speed_mps: 22.352, acceleration_mps2: 10.0, jerk_mps3: 10.0 },
    track_length_m: trackLength,
    lane_lines: laneLines,
    incident_types: INCIDENT_TYPES,
    ...(legacy ? {} : { collision_kinds: COLLISION_KINDS }),
    provenance: { policy: 'synthetic', traffic: 'faithful', seed: 1, track: 'circle', duration_s: seconds, overtake_version: 'synthetic', config_hash: '0',
      ...(cutFrom ? { cut_from: cutFrom } : {}) },
  };
  const writer = new RecordWriter();
  const records = [];
  const frames = [];
  const paths = [];
  const steps = startStep + Math.round(seconds / stepS);
  let s = 100;
  let v = 0;
  let best = 0;
  let since = 0;
  let dist = 0;
  const incidentAt = new Map(incidents.map((i) => [i.step, i]));
  const recorded = [];
  const contacts = []; // {car, first, last, kind, atFault, incidents}
  let lastCollision = null; // the contact of the collision before, while it may go on
  for (let step = startStep; step < steps; ++step) {
    const acc = v < 20 ? 4 : 0;
    v = Math.min(20, v + acc * stepS);
    s += v * stepS;
    dist += v * stepS;
    since += v * stepS;
    best = Math.max(best, since);
    const d = 6;
    const p = at(s, d);
    let cars = [];
    for (let k = 0; k < carCount; ++k) {
      if (churn && (step + 13 * k) % 90 < 6) continue;
      const cs = s + (k - carCount / 2) * 25 + 8;
      const cd = 2 + 4 * (k % 3);
      const cp = at(cs, cd);
      cars.push({ id: churn ? (k * 5003) % 65535 : k, x: cp.x, y: cp.y, yaw: cp.yaw, speed: 18 + (k % 4) });
    }
    if (churn) {
      if (Math.floor(step / 37) % 2 === 1) cars.reverse();
      if (step % 10 < 7) {
        const far = step % 2 === 0 ? 21e6 : -21e6; // metres: near the ends of the i32 range in cm
        cars.splice(step % (cars.length + 1), 0, { id: 65535, x: far, y: -far, yaw: 3.14159, speed: 655.35 });
      }
    }
    const f = {
      step, x: p.x, y: p.y, yaw: p.yaw, speed: v, s: s % trackLength, d,
      accT: acc, accN: (v * v) / R, accTotal: Math.hypot(acc, (v * v) / R), jerk: step % 50 === 0 ? 3 : 0.5,
      distance: dist, distanceSince: since, bestFree: best, cars,
      safety: legacy ? undefined : syntheticSafety(step),
    };
    frames.push(f);
    records.push(writer.frame(f));
    if (step % 2 === 0) {
      const pts = [];
      for (let j = 1; j <= 50; ++j) {
        const q = at(s + j * Math.max(v, 1) * stepS, d);
        pts.push([q.x, q.y]);
      }
      paths.push(pts);
      records.push(writer.path(pts));
    }
    if (checkpointEvery > 0 && (step - startStep) % checkpointEvery === 0) records.push(checkpointRecord(200 + (step % 300)));
    const inc = incidentAt.get(step);
    if (inc) {
      const type = INCIDENT_TYPES.indexOf(inc.type);
      const rec = { step, type, value: inc.value ?? 1, s: s % trackLength, lane: 1, x: p.x, y: p.y };
      if (!legacy) {
        rec.kind = inc.kind === undefined ? 255 : COLLISION_KINDS.indexOf(inc.kind);
        rec.atFault = Boolean(inc.atFault);
        if (!preContacts) {
          rec.contact = -1;
          if (inc.type === 'collision' && rec.kind !== 255) {
            const car = Math.round(rec.value);
            const same = lastCollision && lastCollision.car === car && step - lastCollision.last <= contactGapSteps;
            const c = same ? lastCollision : { index: contacts.length, car, first: step, last: step, s: rec.s, kind: rec.kind, atFault: rec.atFault, incidents: 0 };
            if (!same) contacts.push(c);
            c.last = step;
            c.incidents += 1;
            lastCollision = c;
            rec.contact = c.index;
          }
        }
      }
      recorded.push(rec);
      records.push(incidentRecord(rec));
      since = 0;
    }
  }
  const report = {
    distance_miles: dist / 1609.344, duration_s: seconds, mean_speed_mph: (dist / seconds) * 2.23694,
    best_incident_free_miles: best / 1609.344, incident_counts: {},
    incidents: recorded.map((r) => ({
      type: INCIDENT_TYPES[r.type], t_s: r.step * stepS, s_m: r.s, lane: 1, value: r.value, unit: '',
      ...(r.kind !== undefined && r.kind !== 255 ? { kind: COLLISION_KINDS[r.kind], at_fault: r.atFault } : {}),
      ...(r.contact !== undefined && r.contact >= 0 ? { contact: r.contact } : {}),
    })),
  };
  if (!legacy) {
    const collisions = recorded.filter((r) => INCIDENT_TYPES[r.type] === 'collision');
    report.collisions = preContacts ? {
      total: collisions.length,
      at_fault: collisions.filter((r) => r.atFault).length,
      by_kind: Object.fromEntries(COLLISION_KINDS.map((k, j) => [k, collisions.filter((r) => r.kind === j).length])),
    } : {
      total: contacts.length,
      at_fault: contacts.filter((c) => c.atFault).length,
      by_kind: Object.fromEntries(COLLISION_KINDS.map((k, j) => [k, contacts.filter((c) => c.kind === j).length])),
      rubric_incidents: collisions.length,
      contacts: contacts.map((c) => ({
        car: c.car, t_s: c.first * stepS, end_t_s: (c.last + 1) * stepS, s_m: c.s, lane: 1, kind: COLLISION_KINDS[c.kind],
        at_fault: c.atFault, rubric_incidents: c.incidents,
      })),
    };
    report.safety = {
      min_ttc_ahead_s: 0.8, min_ttc_entering_s: 0.5, min_time_headway_s: 0.6, time_ttc_below_s: 1, share_ttc_below: 1 / seconds,
      time_headway_below_s: 2, share_headway_below: 2 / seconds, near_miss_episodes: 2, ttc_threshold_s: 1.5, headway_threshold_s: 1.0,
    };
  }
  if (end) records.push(endRecord(report));
  return { bytes: encodeReplay(header, records), header, frames, paths, incidents: recorded, records };
}
