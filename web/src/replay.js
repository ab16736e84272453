// The replay decoder: the binary layout of docs/replay.md (version 2), read into typed arrays.
//
// Works in the browser and in Node (the tests). A replay is decoded into one `Replay` whose
// columns are typed arrays indexed by frame (one frame per world step), by car entry, by path
// point and by incident; nothing is built per frame. The same object grows as live records
// arrive (`appendRecords`). Positions are stored as differences from the frame before (zigzag
// varints of fixed-point integers), so records are read in order, from the first, and the
// decoder keeps the last frame's integers.
import { Inflate, unzlibSync } from 'fflate';

export const MAGIC = 'OVTKRPLY';
export const FORMAT_VERSION = 2;
// A checkpoint (the world's state in binary, for `overtake cut`) is of no use to the page: it
// is skipped, as a kind this page does not know would be.
export const RECORD = Object.freeze({ frame: 1, path: 2, incident: 3, end: 4, checkpoint: 5 });
const RECORD_NAMES = { 1: 'frame', 2: 'path', 3: 'incident', 4: 'end', 5: 'checkpoint' };

const CM = 0.01; // metres per centimetre
const YAW_UNIT = 1e-4; // radians per yaw unit
const FRAME_FLOATS_BYTES = 4 * 2 + 4 * 4 + 4 * 3; // s, d, strict figures, distances: 36
const INCIDENT_BYTES = 1 + 4 + 4 + 1 + 4 + 4; // 18
// Added within version 2 at the ends of records; a record of an older writer lacks them.
const FRAME_SAFETY_BYTES = 3 * 2; // u16 TTC ahead, TTC entering a lane, headway (0.01 s)
const COLLISION_CLASS_BYTES = 2; // u8 collision kind, u8 at fault
// Added later within version 2, after the class: u32 the collision's contact, counting from 1
// (0: not a collision, or not known).
const CONTACT_BYTES = 4;
const NO_SECONDS = 65535; // a TTC or headway that is none (or 655.35 s and more)
/// An incident's collision kind when it has none (not a collision, or an older file).
export const NO_COLLISION_KIND = 255;
const MAX_CARS = 255;
const I32_MIN = -2147483648;
const I32_MAX = 2147483647;

// The varint readers' cursor: set it, call them, read it back; `overlong` is set when a
// varint had more than 5 bytes.
let at = 0;
let overlong = false;

// What is wrong when a varint could not be read.
const varintFault = (what, n) => (overlong ? `${what} hold a varint longer than 5 bytes` : `${what} run past the end of the ${n}-byte payload`);

/// An unsigned LEB128 varint of at most 5 bytes in bytes[at, end); -1 when it runs past `end`
/// or is longer (setting `overlong`). Advances `at`.
function readUvarint(bytes, end) {
  if (at >= end) return -1;
  let b = bytes[at++];
  if (b < 0x80) return b;
  let v = b & 0x7f;
  let scale = 0x80;
  for (let i = 1; i < 5; ++i) {
    if (at >= end) return -1;
    b = bytes[at++];
    v += (b & 0x7f) * scale; // arithmetic, not bit operations: up to 35 bits
    if (b < 0x80) return v;
    scale *= 0x80;
  }
  overlong = true;
  return -1;
}

/// A TTC or headway stored in 0.01 s, in seconds (Infinity for none).
const seconds = (cs) => (cs === NO_SECONDS ? Infinity : cs * 0.01);

/// A zigzag varint (a signed difference); NaN when it runs past `end` or is too long.
function readDelta(bytes, end) {
  if (at < end && bytes[at] < 0x80) {
    const z = bytes[at++];
    return (z >>> 1) ^ -(z & 1);
  }
  const z = readUvarint(bytes, end);
  if (z < 0) return NaN;
  return z % 2 === 0 ? z / 2 : -(z + 1) / 2;
}

/// Where a replay of a cut scenario was cut from (the header's `provenance.cut_from`), as
/// {scenario, replay, policy, traffic, seed, atS, startS, incident}; null for a replay that
/// was not cut from another, or whose cut_from has no moment (`at_s`) to show. A text that is
/// missing is '', a number NaN, the seed null.
export function cutOrigin(header) {
  const c = header && header.provenance && header.provenance.cut_from;
  if (!c || typeof c !== 'object' || Array.isArray(c)) return null;
  const text = (v) => (typeof v === 'string' ? v : '');
  const num = (v) => (typeof v === 'number' && Number.isFinite(v) ? v : NaN);
  const atS = num(c.at_s);
  if (atS !== atS) return null;
  return {
    scenario: text(c.scenario), replay: text(c.replay), policy: text(c.policy), traffic: text(c.traffic),
    seed: typeof c.seed === 'number' || typeof c.seed === 'string' ? c.seed : null,
    atS, startS: num(c.start_s), incident: text(c.incident),
  };
}

/// A replay that could not be read at all (bad magic, version, header).
export class ReplayError extends Error {}

// `arr` with room for `need` entries: doubled (or exactly `need` when `exact`).
function grow(arr, need, exact = false) {
  if (need <= arr.length) return arr;
  let cap = exact ? need : Math.max(arr.length * 2, 1024);
  while (cap < need) cap *= 2;
  const next = new arr.constructor(cap);
  next.set(arr);
  return next;
}

/// The decoded replay: header fields and typed-array columns. `frames` is the frame count;
/// arrays may be longer than that (capacity), so always index below the counts.
export class Replay {
  constructor(header) {
    this.header = header;
    this.stepS = Number(header.step_s) || 0.02;
    this.limits = header.limits || {};
    this.car = header.car || { length_m: 4.7, width_m: 1.9 };
    this.incidentTypes = header.incident_types || [];
    this.collisionKinds = Array.isArray(header.collision_kinds) ? header.collision_kinds : [];
    this.laneLines = (header.lane_lines || []).map((l) => Float64Array.from(l));
    this.cutFrom = cutOrigin(header);
    this.frames = 0;
    this.cars = 0; // car entries over all frames
    this.paths = 0;
    this.pathPoints = 0;
    this.incidents = 0;
    this.safetyFrames = 0; // frames that carry TTC and headway (none in an older file)
    this.report = null; // the end record's JSON
    this.ended = false;
    this.problem = null; // why the replay is incomplete (truncated, corrupt), or null
    this.recordsRead = 0;
    this.bodyBytesRead = 0;
    this._pending = null; // live: bytes of a record split over messages
    // The last frame as stored (what the next frame's differences are from): the ego's x, y,
    // yaw, speed; its cars' ids and the same four values (car k at 4k). `_cur*` is the frame
    // being read; `_base` what its cars are coded against (-1: from zero); `_seen` marks ids.
    this._ego = new Int32Array(4);
    this._prevCount = 0;
    this._prevId = new Int32Array(MAX_CARS);
    this._prevVal = new Int32Array(4 * MAX_CARS);
    this._curId = new Int32Array(MAX_CARS);
    this._curVal = new Int32Array(4 * MAX_CARS);
    this._base = new Int32Array(MAX_CARS);
    this._seen = new Uint8Array(65536);
    this._alloc(0, 0, 0, 0);
  }

  _alloc(frames, cars, points, incidents) {
    const f32 = (n) => new Float32Array(n);
    this.step = new Uint32Array(frames);
    this.egoX = f32(frames);
    this.egoY = f32(frames);
    this.egoYaw = f32(frames);
    this.egoSpeed = f32(frames);
    this.egoS = f32(frames);
    this.egoD = f32(frames);
    this.accT = f32(frames);
    this.accN = f32(frames);
    this.accTotal = f32(frames);
    this.jerk = f32(frames);
    this.distance = f32(frames);
    this.distanceSince = f32(frames);
    this.bestFree = f32(frames);
    // seconds; Infinity when there is none (no such car, not closing, or not recorded)
    this.ttcAhead = f32(frames);
    this.ttcEntering = f32(frames);
    this.headway = f32(frames);
    this.time = new Float64Array(frames); // seconds, for the charts
    this.carStart = new Uint32Array(frames + 1);
    this.framePath = new Int32Array(frames); // latest path at or before the frame, or -1
    this.carId = new Uint16Array(cars);
    this.carX = f32(cars);
    this.carY = f32(cars);
    this.carYaw = f32(cars);
    this.carSpeed = f32(cars);
    this.pathFrame = new Int32Array(Math.max(16, frames >> 1));
    this.pathStart = new Uint32Array(Math.max(17, (frames >> 1) + 1));
    this.pathX = f32(points);
    this.pathY = f32(points);
    this.incFrame = new Int32Array(incidents);
    this.incType = new Uint8Array(incidents);
    this.incValue = f32(incidents);
    this.incS = f32(incidents);
    this.incLane = new Uint8Array(incidents);
    this.incX = f32(incidents);
    this.incY = f32(incidents);
    this.incKind = new Uint8Array(incidents); // index into collisionKinds, or NO_COLLISION_KIND
    this.incAtFault = new Uint8Array(incidents);
    // a collision's contact (0-based, as the report's collisions.contacts and an incident's
    // `contact`), or -1 when it has none (not a collision, or a file from before contacts)
    this.incContact = new Float64Array(incidents);
  }

  _growFrames(need, exact = false) {
    if (need <= this.step.length) return;
    for (const k of ['step', 'egoX', 'egoY', 'egoYaw', 'egoSpeed', 'egoS', 'egoD', 'accT', 'accN',
      'accTotal', 'jerk', 'distance', 'distanceSince', 'bestFree', 'ttcAhead', 'ttcEntering', 'headway', 'time',
      'framePath']) {
      this[k] = grow(this[k], need, exact);
    }
    this.carStart = grow(this.carStart, need + 1, exact);
  }

  _growCars(need, exact = false) {
    if (need <= this.carId.length) return;
    for (const k of ['carId', 'carX', 'carY', 'carYaw', 'carSpeed']) this[k] = grow(this[k], need, exact);
  }

  _growPaths(needPaths, needPoints, exact = false) {
    if (needPaths > this.pathFrame.length) this.pathFrame = grow(this.pathFrame, needPaths, exact);
    if (needPaths + 1 > this.pathStart.length) this.pathStart = grow(this.pathStart, needPaths + 1, exact);
    if (needPoints > this.pathX.length) {
      this.pathX = grow(this.pathX, needPoints, exact);
      this.pathY = grow(this.pathY, needPoints, exact);
    }
  }

  _growIncidents(need, exact = false) {
    if (need <= this.incFrame.length) return;
    for (const k of ['incFrame', 'incType', 'incValue', 'incS', 'incLane', 'incX', 'incY', 'incKind', 'incAtFault', 'incContact']) {
      this[k] = grow(this[k], need, exact);
    }
  }

  /// Makes room for the records in `bytes` at once (a quick pass over their heads and counts),
  /// so that a whole file is read without growing the columns again and again.
  reserve(bytes) {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const total = bytes.length;
    let frames = 0;
    let cars = 0;
    let paths = 0;
    let points = 0;
    let incidents = 0;
    for (let off = 0; off + 5 <= total;) {
      const kind = bytes[off];
      const p = off + 5;
      const end = p + view.getUint32(off + 1, true);
      if (end > total) break;
      if (kind === RECORD.frame) {
        frames += 1;
        let q = p + 4; // after the step: the ego's four varints, the floats, the car count
        for (let v = 0; v < 4 && q < end; ++q) if (bytes[q] < 0x80) v += 1;
        q += FRAME_FLOATS_BYTES;
        if (q < end) cars += bytes[q];
      } else if (kind === RECORD.path && end - p >= 2) {
        paths += 1;
        points += view.getUint16(p, true);
      } else if (kind === RECORD.incident) {
        incidents += 1;
      }
      off = end;
    }
    this._growFrames(this.frames + frames, true);
    this._growCars(this.cars + cars, true);
    this._growPaths(this.paths + paths, this.pathPoints + points, true);
    this._growIncidents(this.incidents + incidents, true);
  }

  /// Reads whole records from `bytes` (a Uint8Array of kind, length, payload, ...). Returns
  /// the number of bytes consumed; stops before a record that is cut short, or at the first
  /// malformed one (setting `problem`). `live` keeps a trailing partial record for later.
  appendRecords(bytes, { live = false } = {}) {
    if (this._pending && this._pending.length) {
      const joined = new Uint8Array(this._pending.length + bytes.length);
      joined.set(this._pending);
      joined.set(bytes, this._pending.length);
      bytes = joined;
      this._pending = null;
    }
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const total = bytes.length;
    let off = 0;
    while (off < total) {
      if (this.ended) {
        this.problem = this.problem || `data after the end record (record ${this.recordsRead + 1})`;
        break;
      }
      if (off + 5 > total) {
        if (live) this._pending = bytes.slice(off);
        else this.problem = `record ${this.recordsRead + 1} at byte ${off} of the data is cut short (its 5-byte head is incomplete)`;
        break;
      }
      const kind = bytes[off];
      const n = view.getUint32(off + 1, true);
      if (off + 5 + n > total) {
        if (live) this._pending = bytes.slice(off);
        else {
          this.problem = `record ${this.recordsRead + 1} (${RECORD_NAMES[kind] || `kind ${kind}`}) at byte ${off} of the data ` +
            `is cut short: it needs ${n} bytes, ${total - off - 5} remain`;
        }
        break;
      }
      const p = off + 5;
      const why = this._record(kind, view, bytes, p, n);
      if (why) {
        this.problem = `record ${this.recordsRead + 1} (${RECORD_NAMES[kind]}) at byte ${off} of the data is malformed: ${why}`;
        break;
      }
      off = p + n;
      this.recordsRead += 1;
    }
    this.bodyBytesRead += off;
    return off;
  }

  // Decodes one record; returns an error text or null.
  _record(kind, v, bytes, p, n) {
    switch (kind) {
      case RECORD.frame: {
        const end = p + n;
        if (n < 4) return `a frame needs at least 4 bytes, has ${n}`;
        const i = this.frames;
        const stepIndex = v.getUint32(p, true);
        if (i > 0 && stepIndex <= this.step[i - 1]) {
          return `step ${stepIndex} does not follow step ${this.step[i - 1]}`;
        }
        at = p + 4;
        overlong = false;
        const eg = this._ego;
        const ex = eg[0] + readDelta(bytes, end);
        const ey = eg[1] + readDelta(bytes, end);
        const eyaw = eg[2] + readDelta(bytes, end);
        const espeed = eg[3] + readDelta(bytes, end);
        if (ex !== ex || ey !== ey || eyaw !== eyaw || espeed !== espeed) {
          return varintFault('the ego\'s position and speed', n);
        }
        if (ex < I32_MIN || ex > I32_MAX || ey < I32_MIN || ey > I32_MAX || eyaw < -32768 || eyaw > 32767 ||
            espeed < 0 || espeed > 65535) {
          return `the ego's position or speed is out of range (${ex}, ${ey}, ${eyaw}, ${espeed})`;
        }
        if (at + FRAME_FLOATS_BYTES + 1 > end) {
          return `a frame needs ${at + FRAME_FLOATS_BYTES + 1 - p} bytes up to its car count, has ${n}`;
        }
        this._growFrames(i + 1);
        this.step[i] = stepIndex;
        this.time[i] = stepIndex * this.stepS;
        this.egoX[i] = ex * CM;
        this.egoY[i] = ey * CM;
        this.egoYaw[i] = eyaw * YAW_UNIT;
        this.egoSpeed[i] = espeed * CM;
        this.egoS[i] = v.getFloat32(at, true);
        this.egoD[i] = v.getFloat32(at + 4, true);
        this.accT[i] = v.getFloat32(at + 8, true);
        this.accN[i] = v.getFloat32(at + 12, true);
        this.accTotal[i] = v.getFloat32(at + 16, true);
        this.jerk[i] = v.getFloat32(at + 20, true);
        this.distance[i] = v.getFloat32(at + 24, true);
        this.distanceSince[i] = v.getFloat32(at + 28, true);
        this.bestFree[i] = v.getFloat32(at + 32, true);
        const c = bytes[at + 36];
        at += FRAME_FLOATS_BYTES + 1;
        const why = this._cars(bytes, end, c, n);
        if (why) return why;
        // TTC and headway, after the cars (added within version 2): an older frame has none,
        // and bytes beyond them are for later additions
        if (end - at >= FRAME_SAFETY_BYTES) {
          this.ttcAhead[i] = seconds(v.getUint16(at, true));
          this.ttcEntering[i] = seconds(v.getUint16(at + 2, true));
          this.headway[i] = seconds(v.getUint16(at + 4, true));
          this.safetyFrames += 1;
        } else {
          this.ttcAhead[i] = Infinity;
          this.ttcEntering[i] = Infinity;
          this.headway[i] = Infinity;
        }
        this.framePath[i] = this.paths - 1;
        eg[0] = ex;
        eg[1] = ey;
        eg[2] = eyaw;
        eg[3] = espeed;
        this.carStart[i] = this.cars;
        this.cars += c;
        this.carStart[i + 1] = this.cars;
        this.frames = i + 1;
        return null;
      }
      case RECORD.path: {
        if (n < 2) return 'a path needs its 2-byte count';
        if (this.frames === 0) return 'a path before the first frame';
        const m = v.getUint16(p, true);
        const end = p + n;
        const k = this.paths;
        this._growPaths(k + 1, this.pathPoints + m);
        const px = this.pathX;
        const py = this.pathY;
        const o = this.pathPoints;
        // the first point from the ego of the frame before, the others from the point before
        let x = this._ego[0];
        let y = this._ego[1];
        let q = p + 2;
        let b = 0;
        overlong = false;
        for (let j = 0; j < m; ++j) {
          // one-byte differences inline (most of them), longer ones by readDelta
          if (q < end && (b = bytes[q]) < 0x80) {
            x += (b >>> 1) ^ -(b & 1);
            ++q;
          } else {
            at = q;
            x += readDelta(bytes, end);
            q = at;
          }
          if (q < end && (b = bytes[q]) < 0x80) {
            y += (b >>> 1) ^ -(b & 1);
            ++q;
          } else {
            at = q;
            y += readDelta(bytes, end);
            q = at;
          }
          if (x !== x || y !== y) return varintFault(`its ${m} points (from point ${j + 1})`, n);
          if (x < I32_MIN || x > I32_MAX || y < I32_MIN || y > I32_MAX) return `point ${j + 1} is out of range (${x}, ${y})`;
          px[o + j] = x * CM;
          py[o + j] = y * CM;
        }
        this.pathFrame[k] = this.frames - 1;
        this.pathStart[k] = o;
        this.pathPoints = o + m;
        this.pathStart[k + 1] = this.pathPoints;
        this.paths = k + 1;
        this.framePath[this.frames - 1] = k;
        return null;
      }
      case RECORD.incident: {
        if (n < INCIDENT_BYTES) return `an incident needs ${INCIDENT_BYTES} bytes, has ${n}`;
        if (this.frames === 0) return 'an incident before the first frame';
        // the collision's class (added within version 2; an 18-byte incident has none)
        let kind = NO_COLLISION_KIND;
        let atFault = 0;
        if (n >= INCIDENT_BYTES + COLLISION_CLASS_BYTES) {
          kind = bytes[p + INCIDENT_BYTES];
          atFault = bytes[p + INCIDENT_BYTES + 1];
          if (kind === NO_COLLISION_KIND) {
            atFault = 0; // not a collision: its fault byte says nothing
          } else if (kind >= this.collisionKinds.length) {
            return `collision kind ${kind} is not one of the header's ${this.collisionKinds.length} collision_kinds`;
          } else if (atFault > 1) {
            return `its at-fault byte is ${atFault}, not 0 or 1`;
          }
        }
        // the collision's contact (added later within version 2): a number from 1, 0 for none;
        // only a classified collision (of the header's type "collision") has one
        let contact = -1;
        if (n >= INCIDENT_BYTES + COLLISION_CLASS_BYTES + CONTACT_BYTES) {
          const number = v.getUint32(p + INCIDENT_BYTES + COLLISION_CLASS_BYTES, true);
          const named = this.incidentTypes.length > 0;  // a header that names the types
          if (number > 0 && (kind === NO_COLLISION_KIND ||
                             (named && this.incidentTypes[bytes[p]] !== 'collision'))) {
            return `contact number ${number} on an incident that is no classified collision`;
          }
          contact = number - 1;
        }
        const k = this.incidents;
        this._growIncidents(k + 1);
        this.incFrame[k] = this.frames - 1;
        this.incType[k] = bytes[p];
        this.incValue[k] = v.getFloat32(p + 1, true);
        this.incS[k] = v.getFloat32(p + 5, true);
        this.incLane[k] = bytes[p + 9];
        this.incX[k] = v.getInt32(p + 10, true) * CM;
        this.incY[k] = v.getInt32(p + 14, true) * CM;
        this.incKind[k] = kind;
        this.incAtFault[k] = atFault;
        this.incContact[k] = contact;
        this.incidents = k + 1;
        return null;
      }
      case RECORD.end: {
        try {
          this.report = JSON.parse(new TextDecoder().decode(bytes.subarray(p, p + n)));
        } catch (e) {
          return `the end record's report is not JSON (${e.message})`;
        }
        this.ended = true;
        return null;
      }
      case RECORD.checkpoint:
        return null; // the C++ side's, for `overtake cut`
      default:
        return null; // unknown kinds are skipped
    }
  }

  // A frame's `c` cars from `at`: ids, then x, y, yaw and speed each as a column of
  // differences from the same car in the frame before (from zero for a car that was not in
  // it). Writes the car columns from index `this.cars` on and, when the frame is whole, makes
  // it the frame before. Returns an error text or null.
  _cars(bytes, end, c, n) {
    const base = this.cars;
    this._growCars(base + c);
    const ids = this._curId;
    const ref = this._base;
    const prevId = this._prevId;
    const prevCount = this._prevCount;
    const carId = this.carId;
    let same = c === prevCount; // the same ids in the same order as the frame before
    let q = at;
    let b = 0;
    for (let k = 0; k < c; ++k) {
      let id;
      if (q < end && (b = bytes[q]) < 0x80) {
        id = b;
        ++q;
      } else {
        at = q;
        id = readUvarint(bytes, end);
        q = at;
        if (id < 0) return varintFault(`the ids of its ${c} cars`, n);
        if (id > 65535) return `car id ${id} is above 65535`;
      }
      ids[k] = id;
      carId[base + k] = id;
      if (same && prevId[k] !== id) same = false;
    }
    at = q;
    if (same) {
      // unique, as the frame before's were
      for (let k = 0; k < c; ++k) ref[k] = k;
    } else {
      const seen = this._seen;
      for (let k = 0; k < c; ++k) {
        if (seen[ids[k]]) {
          for (let j = 0; j < k; ++j) seen[ids[j]] = 0;
          return `car id ${ids[k]} appears twice`;
        }
        seen[ids[k]] = 1;
      }
      for (let k = 0; k < c; ++k) {
        const id = ids[k];
        seen[id] = 0;
        let j = k < prevCount && prevId[k] === id ? k : -1;
        if (j < 0) {
          for (let i = 0; i < prevCount; ++i) {
            if (prevId[i] === id) {
              j = i;
              break;
            }
          }
        }
        ref[k] = j;
      }
    }
    const why = this._column(bytes, end, c, n, base, 0, this.carX, CM, I32_MIN, I32_MAX, 'x') ||
      this._column(bytes, end, c, n, base, 1, this.carY, CM, I32_MIN, I32_MAX, 'y') ||
      this._column(bytes, end, c, n, base, 2, this.carYaw, YAW_UNIT, -32768, 32767, 'yaw') ||
      this._column(bytes, end, c, n, base, 3, this.carSpeed, CM, 0, 65535, 'speed');
    if (why) return why;
    // this frame is now the frame before
    const prevVal = this._prevVal;
    this._prevId = ids;
    this._curId = prevId;
    this._prevVal = this._curVal;
    this._curVal = prevVal;
    this._prevCount = c;
    return null;
  }

  // One column of a frame's cars from `at`: value f (x, y, yaw, speed) of each car, as a
  // difference from `_base`'s car in the frame before, into `_curVal` and out[base + k] (times
  // `scale`). Returns an error text or null.
  _column(bytes, end, c, n, base, f, out, scale, min, max, name) {
    const ref = this._base;
    const prevVal = this._prevVal;
    const cur = this._curVal;
    let q = at;
    let b = 0;
    for (let k = 0; k < c; ++k) {
      let d;
      if (q < end && (b = bytes[q]) < 0x80) {
        d = (b >>> 1) ^ -(b & 1);
        ++q;
      } else {
        at = q;
        d = readDelta(bytes, end);
        q = at;
        if (d !== d) return varintFault(`the ${name} of its ${c} cars`, n);
      }
      const j = ref[k];
      const val = (j >= 0 ? prevVal[4 * j + f] : 0) + d;
      if (val < min || val > max) return `a car's ${name} comes to ${val}, outside [${min}, ${max}]`;
      cur[4 * k + f] = val;
      out[base + k] = val * scale;
    }
    at = q;
    return null;
  }

  /// The index of the frame whose step is `step`, or of the last frame before it (0 if none).
  frameOfStep(step) {
    let lo = 0;
    let hi = this.frames - 1;
    if (hi < 0) return 0;
    if (step <= this.step[0]) return 0;
    if (step >= this.step[hi]) return hi;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (this.step[mid] <= step) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  /// The name of an incident type index.
  incidentTypeName(t) {
    return this.incidentTypes[t] || `type ${t}`;
  }

  /// Incident k's collision class, {kind (its name), atFault}, or null when it has none (not
  /// a collision, or a file written before collisions were classified).
  incidentClass(k) {
    const kind = this.incKind[k];
    if (kind === NO_COLLISION_KIND) return null;
    return { kind: this.collisionKinds[kind] || `kind ${kind}`, atFault: this.incAtFault[k] === 1 };
  }

  /// Incident k's contact: its index in the run's contacts (from 0; the banner says "contact
  /// k + 1"), or -1 when it has none (not a collision, or a file from before contacts).
  incidentContact(k) {
    return k >= 0 && k < this.incidents ? this.incContact[k] : -1;
  }

  /// The contacts the incidents name, in order of their first incident: [{contact, first (its
  /// first incident), incidents (how many of the rubric's latched collision incidents it
  /// has)}]; and for each incident whether it repeats a contact named before (`repeat`, a
  /// Uint8Array by incident). Collisions without a contact are not in it.
  contacts() {
    const byNumber = new Map();
    const list = [];
    const repeat = new Uint8Array(this.incidents);
    for (let k = 0; k < this.incidents; ++k) {
      const c = this.incContact[k];
      if (c < 0) continue;
      const known = byNumber.get(c);
      if (known) {
        known.incidents += 1;
        repeat[k] = 1;
      } else {
        const entry = { contact: c, first: k, incidents: 1 };
        byNumber.set(c, entry);
        list.push(entry);
      }
    }
    return { list, byNumber, repeat };
  }

  /// A sentence on how much was read, for warnings.
  summary() {
    const t = this.frames ? this.time[this.frames - 1] : 0;
    // a cut scenario's frames keep the run's clock: they start later than 0
    const span = this.frames && this.step[0] > 0 ? `t ${this.time[0].toFixed(2)} to ${t.toFixed(2)} s` : `${t.toFixed(2)} s`;
    return `${this.frames} frames (${span}), ${this.paths} paths, ${this.incidents} incidents`;
  }
}

/// The header JSON text of a replay file, parsed and checked.
export function parseHeader(text) {
  let header;
  try {
    header = JSON.parse(text);
  } catch (e) {
    throw new ReplayError(`the header is not JSON (${e.message})`);
  }
  if (!header || typeof header !== 'object') throw new ReplayError('the header is not a JSON object');
  if (header.format !== undefined && header.format !== 'overtake-replay') {
    throw new ReplayError(`the header's format is '${header.format}', not 'overtake-replay'`);
  }
  if (header.version !== undefined && header.version !== FORMAT_VERSION) {
    throw new ReplayError(`the header says format version ${header.version}; this page reads version ${FORMAT_VERSION}` +
      (header.version === 1 ? ' (version 1 is no longer supported: re-record the run with this build of overtake)' : ''));
  }
  return header;
}

/// Adler-32 of bytes (RFC 1950), as an unsigned 32-bit number.
export function adler32(bytes) {
  let a = 1;
  let b = 0;
  const n = bytes.length;
  let i = 0;
  while (i < n) {
    const end = Math.min(i + 3800, n); // keeps b below 2^53 before the modulo
    for (; i < end; ++i) {
      a += bytes[i];
      b += a;
    }
    a %= 65521;
    b %= 65521;
  }
  return ((b << 16) | a) >>> 0;
}

// Inflates a zlib stream. Returns {data, problem}: on a fault, data holds what came out before it.
function inflateZlib(body, bodyOffset) {
  if (body.length < 2) return { data: new Uint8Array(0), problem: `the data stream is missing (file ends at byte ${bodyOffset + body.length})` };
  const cmf = body[0];
  const flg = body[1];
  if ((cmf & 0x0f) !== 8 || ((cmf << 8) | flg) % 31 !== 0) {
    return { data: new Uint8Array(0), problem: `the data stream at byte ${bodyOffset} is not a zlib stream` };
  }
  let data = null;
  try {
    data = unzlibSync(body);
  } catch {
    data = null;
  }
  if (data) {
    const want = body.length >= 6 ? new DataView(body.buffer, body.byteOffset + body.length - 4, 4).getUint32(0, false) : -1;
    if (adler32(data) !== want) {
      return { data, problem: `the data stream's checksum does not match: the file is corrupt (or truncated near byte ${bodyOffset + body.length})` };
    }
    return { data, problem: null };
  }
  // The slow path: inflate in chunks to keep what comes out before the fault.
  const chunks = [];
  let size = 0;
  const inf = new Inflate((chunk) => {
    if (chunk.length) {
      chunks.push(chunk);
      size += chunk.length;
    }
  });
  const raw = body.subarray(2);
  const CHUNK = 16384;
  let at = 0;
  let problem = null;
  try {
    // every byte as non-final chunks (fflate hands out all it can inflate of them), then an
    // empty final one: a stream cut short still gives everything before the cut
    for (; at < raw.length; at += CHUNK) inf.push(raw.subarray(at, Math.min(at + CHUNK, raw.length)), false);
    at = Math.max(0, raw.length - 1);
    inf.push(new Uint8Array(0), true);
    problem = `the data stream has trailing bytes or a bad checksum: the file is corrupt`;
  } catch (e) {
    const msg = String((e && e.message) || e);
    problem = /unexpected EOF/i.test(msg)
      ? `the data stream ends early: the file is truncated (it ends at byte ${bodyOffset + body.length})`
      : `the data stream is corrupt near byte ${bodyOffset + 2 + at} (${msg})`;
  }
  const out = new Uint8Array(size);
  let o = 0;
  for (const c of chunks) {
    out.set(c, o);
    o += c.length;
  }
  return { data: out, problem };
}

// Inflates with the platform's DecompressionStream (native zlib: several times faster than
// fflate, and it checks the Adler-32). Resolves to the data, or null when the platform has no
// such stream or the stream fails (the caller then takes the fflate path, which tells what is
// wrong and keeps what comes before the fault).
async function inflateNative(body) {
  if (typeof DecompressionStream !== 'function' || typeof Blob !== 'function') return null;
  try {
    const stream = new Blob([body]).stream().pipeThrough(new DecompressionStream('deflate'));
    const reader = stream.getReader();
    const chunks = [];
    let size = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      chunks.push(value);
      size += value.length;
    }
    const out = new Uint8Array(size);
    let o = 0;
    for (const c of chunks) {
      out.set(c, o);
      o += c.length;
    }
    return out;
  } catch {
    return null;
  }
}

// The parts of a replay file before its body: the header, and where the body starts.
function readPreamble(fileBytes, name) {
  const bytes = fileBytes instanceof Uint8Array ? fileBytes : new Uint8Array(fileBytes);
  if (bytes.length < 16) throw new ReplayError(`${name} is too short to be a replay (${bytes.length} bytes)`);
  const magic = String.fromCharCode(...bytes.subarray(0, 8));
  if (magic !== MAGIC) throw new ReplayError(`${name} is not an overtake replay (it does not start with ${MAGIC})`);
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const version = dv.getUint32(8, true);
  if (version === 1) {
    throw new ReplayError(`${name} is replay format version 1, which is no longer supported: re-record the run with this build of overtake (it writes version ${FORMAT_VERSION})`);
  }
  if (version !== FORMAT_VERSION) {
    throw new ReplayError(`${name} is replay format version ${version}; this page reads version ${FORMAT_VERSION}`);
  }
  const h = dv.getUint32(12, true);
  if (16 + h > bytes.length) {
    throw new ReplayError(`${name} is truncated: its header needs ${h} bytes, the file has ${bytes.length - 16} after byte 16`);
  }
  let header;
  try {
    header = parseHeader(new TextDecoder('utf-8', { fatal: true }).decode(bytes.subarray(16, 16 + h)));
  } catch (e) {
    throw new ReplayError(`${name}: ${e.message}`);
  }
  return { bytes, header, bodyAt: 16 + h };
}

function finish(replay, data, problem, name) {
  replay.reserve(data);
  replay.appendRecords(data);
  const problems = [];
  if (problem) problems.push(problem);
  if (replay.problem) problems.push(replay.problem);
  if (!replay.ended && !problems.length) problems.push('it has no end record: the run was cut off');
  replay.problem = problems.length ? `${name}: ${problems.join('; ')}` : null;
  return replay;
}

/// Decodes a whole replay file. Throws ReplayError when nothing can be read (bad magic,
/// version or header); otherwise returns a Replay whose `problem` says what went wrong, if
/// anything (truncated, corrupt, no end record), with the records read before the fault.
export function decodeReplay(fileBytes, name = 'the replay') {
  const { bytes, header, bodyAt } = readPreamble(fileBytes, name);
  const { data, problem } = inflateZlib(bytes.subarray(bodyAt), bodyAt);
  return finish(new Replay(header), data, problem, name);
}

/// As decodeReplay, faster where the platform inflates natively (browsers, Node 18+).
export async function decodeReplayAsync(fileBytes, name = 'the replay') {
  const { bytes, header, bodyAt } = readPreamble(fileBytes, name);
  const body = bytes.subarray(bodyAt);
  const native = body.length >= 6 ? await inflateNative(body) : null;
  const { data, problem } = native ? { data: native, problem: null } : inflateZlib(body, bodyAt);
  return finish(new Replay(header), data, problem, name);
}

/// Base64 text (whitespace allowed) to bytes.
export function base64ToBytes(text) {
  const clean = text.replace(/[\s]/g, '');
  if (typeof Uint8Array.fromBase64 === 'function') return Uint8Array.fromBase64(clean);
  const table = new Uint8Array(128).fill(255);
  const alphabet = 'ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/';
  for (let i = 0; i < 64; ++i) table[alphabet.charCodeAt(i)] = i;
  table['-'.charCodeAt(0)] = 62;
  table['_'.charCodeAt(0)] = 63;
  let len = clean.length;
  while (len > 0 && clean.charCodeAt(len - 1) === 61) --len; // '='
  const out = new Uint8Array((len * 3) >> 2);
  let o = 0;
  let i = 0;
  for (; i + 4 <= len; i += 4) {
    const a = table[clean.charCodeAt(i)];
    const b = table[clean.charCodeAt(i + 1)];
    const c = table[clean.charCodeAt(i + 2)];
    const d = table[clean.charCodeAt(i + 3)];
    if ((a | b | c | d) & 0x80) throw new Error(`not base64 near character ${i}`);
    out[o++] = (a << 2) | (b >> 4);
    out[o++] = ((b & 15) << 4) | (c >> 2);
    out[o++] = ((c & 3) << 6) | d;
  }
  const rest = len - i;
  if (rest === 1) throw new Error('base64 text has a stray last character');
  if (rest >= 2) {
    const a = table[clean.charCodeAt(i)];
    const b = table[clean.charCodeAt(i + 1)];
    out[o++] = (a << 2) | (b >> 4);
    if (rest === 3) {
      const c = table[clean.charCodeAt(i + 2)];
      out[o++] = ((b & 15) << 4) | (c >> 2);
    }
  }
  return out;
}
