// The replay decoder: the binary layout of docs/replay.md (version 1), read into typed arrays.
//
// Works in the browser and in Node (the tests). A replay is decoded into one `Replay` whose
// columns are typed arrays indexed by frame (one frame per world step), by car entry, by path
// point and by incident; nothing is built per frame. The same object grows as live records
// arrive (`appendRecords`).
import { Inflate, unzlibSync } from 'fflate';

export const MAGIC = 'OVTKRPLY';
export const FORMAT_VERSION = 1;
export const RECORD = Object.freeze({ frame: 1, path: 2, incident: 3, end: 4 });
const RECORD_NAMES = { 1: 'frame', 2: 'path', 3: 'incident', 4: 'end' };

const CM = 0.01; // metres per centimetre
const YAW_UNIT = 1e-4; // radians per yaw unit
const FRAME_FIXED_BYTES = 4 + 4 + 4 + 2 + 2 + 4 * 2 + 4 * 4 + 4 * 3 + 1; // 53
const CAR_BYTES = 2 + 4 + 4 + 2 + 2; // 14
const INCIDENT_BYTES = 1 + 4 + 4 + 1 + 4 + 4; // 18

/// A replay that could not be read at all (bad magic, version, header).
export class ReplayError extends Error {}

function grow(arr, need) {
  if (need <= arr.length) return arr;
  let cap = Math.max(arr.length * 2, 1024);
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
    this.laneLines = (header.lane_lines || []).map((l) => Float64Array.from(l));
    this.frames = 0;
    this.cars = 0; // car entries over all frames
    this.paths = 0;
    this.pathPoints = 0;
    this.incidents = 0;
    this.report = null; // the end record's JSON
    this.ended = false;
    this.problem = null; // why the replay is incomplete (truncated, corrupt), or null
    this.recordsRead = 0;
    this.bodyBytesRead = 0;
    this._pending = null; // live: bytes of a record split over messages
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
  }

  _growFrames(need) {
    if (need <= this.step.length) return;
    for (const k of ['step', 'egoX', 'egoY', 'egoYaw', 'egoSpeed', 'egoS', 'egoD', 'accT', 'accN',
      'accTotal', 'jerk', 'distance', 'distanceSince', 'bestFree', 'time', 'framePath']) {
      this[k] = grow(this[k], need);
    }
    this.carStart = grow(this.carStart, need + 1);
  }

  _growCars(need) {
    if (need <= this.carId.length) return;
    for (const k of ['carId', 'carX', 'carY', 'carYaw', 'carSpeed']) this[k] = grow(this[k], need);
  }

  _growPaths(needPaths, needPoints) {
    if (needPaths > this.pathFrame.length) this.pathFrame = grow(this.pathFrame, needPaths);
    if (needPaths + 1 > this.pathStart.length) this.pathStart = grow(this.pathStart, needPaths + 1);
    if (needPoints > this.pathX.length) {
      this.pathX = grow(this.pathX, needPoints);
      this.pathY = grow(this.pathY, needPoints);
    }
  }

  _growIncidents(need) {
    if (need <= this.incFrame.length) return;
    for (const k of ['incFrame', 'incType', 'incValue', 'incS', 'incLane', 'incX', 'incY']) {
      this[k] = grow(this[k], need);
    }
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
        if (n < FRAME_FIXED_BYTES) return `a frame needs at least ${FRAME_FIXED_BYTES} bytes, has ${n}`;
        const c = bytes[p + FRAME_FIXED_BYTES - 1];
        if (n !== FRAME_FIXED_BYTES + c * CAR_BYTES) {
          return `a frame with ${c} cars needs ${FRAME_FIXED_BYTES + c * CAR_BYTES} bytes, has ${n}`;
        }
        const i = this.frames;
        this._growFrames(i + 1);
        const stepIndex = v.getUint32(p, true);
        if (i > 0 && stepIndex <= this.step[i - 1]) {
          return `step ${stepIndex} does not follow step ${this.step[i - 1]}`;
        }
        this.step[i] = stepIndex;
        this.time[i] = stepIndex * this.stepS;
        this.egoX[i] = v.getInt32(p + 4, true) * CM;
        this.egoY[i] = v.getInt32(p + 8, true) * CM;
        this.egoYaw[i] = v.getInt16(p + 12, true) * YAW_UNIT;
        this.egoSpeed[i] = v.getUint16(p + 14, true) * CM;
        this.egoS[i] = v.getFloat32(p + 16, true);
        this.egoD[i] = v.getFloat32(p + 20, true);
        this.accT[i] = v.getFloat32(p + 24, true);
        this.accN[i] = v.getFloat32(p + 28, true);
        this.accTotal[i] = v.getFloat32(p + 32, true);
        this.jerk[i] = v.getFloat32(p + 36, true);
        this.distance[i] = v.getFloat32(p + 40, true);
        this.distanceSince[i] = v.getFloat32(p + 44, true);
        this.bestFree[i] = v.getFloat32(p + 48, true);
        this.framePath[i] = this.paths - 1;
        const base = this.cars;
        this._growCars(base + c);
        let q = p + FRAME_FIXED_BYTES;
        for (let k = 0; k < c; ++k, q += CAR_BYTES) {
          const j = base + k;
          this.carId[j] = v.getUint16(q, true);
          this.carX[j] = v.getInt32(q + 2, true) * CM;
          this.carY[j] = v.getInt32(q + 6, true) * CM;
          this.carYaw[j] = v.getInt16(q + 10, true) * YAW_UNIT;
          this.carSpeed[j] = v.getUint16(q + 12, true) * CM;
        }
        this.carStart[i] = base;
        this.cars = base + c;
        this.carStart[i + 1] = this.cars;
        this.frames = i + 1;
        return null;
      }
      case RECORD.path: {
        if (n < 2) return 'a path needs its 2-byte count';
        const m = v.getUint16(p, true);
        if (n !== 2 + m * 8) return `a path of ${m} points needs ${2 + m * 8} bytes, has ${n}`;
        if (this.frames === 0) return 'a path before the first frame';
        const k = this.paths;
        this._growPaths(k + 1, this.pathPoints + m);
        this.pathFrame[k] = this.frames - 1;
        this.pathStart[k] = this.pathPoints;
        let q = p + 2;
        for (let j = 0; j < m; ++j, q += 8) {
          this.pathX[this.pathPoints + j] = v.getInt32(q, true) * CM;
          this.pathY[this.pathPoints + j] = v.getInt32(q + 4, true) * CM;
        }
        this.pathPoints += m;
        this.pathStart[k + 1] = this.pathPoints;
        this.paths = k + 1;
        this.framePath[this.frames - 1] = k;
        return null;
      }
      case RECORD.incident: {
        if (n !== INCIDENT_BYTES) return `an incident needs ${INCIDENT_BYTES} bytes, has ${n}`;
        if (this.frames === 0) return 'an incident before the first frame';
        const k = this.incidents;
        this._growIncidents(k + 1);
        this.incFrame[k] = this.frames - 1;
        this.incType[k] = bytes[p];
        this.incValue[k] = v.getFloat32(p + 1, true);
        this.incS[k] = v.getFloat32(p + 5, true);
        this.incLane[k] = bytes[p + 9];
        this.incX[k] = v.getInt32(p + 10, true) * CM;
        this.incY[k] = v.getInt32(p + 14, true) * CM;
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
      default:
        return null; // unknown kinds are skipped
    }
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

  /// A sentence on how much was read, for warnings.
  summary() {
    const t = this.frames ? this.time[this.frames - 1] : 0;
    return `${this.frames} frames (${t.toFixed(2)} s), ${this.paths} paths, ${this.incidents} incidents`;
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
    for (; at + CHUNK < raw.length; at += CHUNK) inf.push(raw.subarray(at, at + CHUNK), false);
    inf.push(raw.subarray(at), true);
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
