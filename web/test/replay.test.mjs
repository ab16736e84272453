// The decoder against the test writer (docs/replay.md): round trip, truncation, corruption,
// live records split over messages, the fields added within version 2 (TTC and headway,
// collision classes, contact numbers) and files from before them.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import {
  adler32, base64ToBytes, cutOrigin, decodeReplay, decodeReplayAsync, NO_COLLISION_KIND, parseHeader, RECORD, Replay, ReplayError,
} from '../src/replay.js';
import { cutCommand, cutOriginText, REPLAY_PLACEHOLDER, shellWord } from '../src/viewer/format.js';
import {
  centiseconds, checkpointRecord, cm, COLLISION_KINDS, concat, encodeReplay, incidentRecord, RecordWriter, speedUnits, syntheticDrive,
  syntheticSafety, yawUnits,
} from './encode.mjs';

const close = (a, b, tol, what) => assert.ok(Math.abs(a - b) <= tol, `${what}: ${a} vs ${b}`);

test('round trip: every frame, car, path and incident comes back', () => {
  const drive = syntheticDrive({ seconds: 6, incidents: [{ step: 120, type: 'collision', value: 3 }, { step: 200, type: 'max_jerk', value: 12.5 }] });
  const r = decodeReplay(drive.bytes);
  assert.equal(r.problem, null);
  assert.equal(r.frames, drive.frames.length);
  assert.equal(r.cars, drive.frames.length * 12);
  assert.equal(r.paths, drive.frames.length / 2);
  assert.equal(r.incidents, 2);
  assert.equal(r.incidentTypeName(r.incType[0]), 'collision');
  assert.equal(r.incFrame[1], 200);
  close(r.incValue[1], 12.5, 1e-6, 'incident value');
  assert.ok(r.ended);
  assert.equal(r.report.incidents.length, 2);
  for (const i of [0, 1, 137, drive.frames.length - 1]) {
    const f = drive.frames[i];
    assert.equal(r.step[i], f.step);
    close(r.egoX[i], f.x, 0.006, 'x');
    close(r.egoY[i], f.y, 0.006, 'y');
    close(r.egoSpeed[i], f.speed, 0.006, 'speed');
    close(r.accTotal[i], f.accTotal, 1e-5, 'acc');
    close(r.bestFree[i], f.bestFree, 1e-3, 'best');
    const c0 = r.carStart[i];
    assert.equal(r.carStart[i + 1] - c0, 12);
    assert.equal(r.carId[c0 + 5], 5);
    close(r.carX[c0 + 5], f.cars[5].x, 0.006, 'car x');
    close(r.carSpeed[c0 + 5], f.cars[5].speed, 0.006, 'car speed');
    let dyaw = Math.abs(r.egoYaw[i] - f.yaw) % (2 * Math.PI);
    dyaw = Math.min(dyaw, 2 * Math.PI - dyaw);
    assert.ok(dyaw < 1e-3, `yaw ${r.egoYaw[i]} vs ${f.yaw}`);
  }
  // frame 3's path is the one sent at frame 2
  assert.equal(r.framePath[3], 1);
  assert.equal(r.pathFrame[1], 2);
  assert.equal(r.pathStart[2] - r.pathStart[1], 50);
  assert.equal(r.frameOfStep(150), 150);
  assert.equal(r.frameOfStep(1e9), r.frames - 1);
});

test('a truncated file keeps the frames before the cut and says so', () => {
  const drive = syntheticDrive({ seconds: 20 });
  const body = 16 + new DataView(drive.bytes.buffer).getUint32(12, true);
  const cut = drive.bytes.subarray(0, body + Math.floor((drive.bytes.length - body) * 0.6));
  const r = decodeReplay(cut, 'cut.otr');
  assert.match(r.problem, /cut\.otr/);
  assert.match(r.problem, /truncated|ends early/);
  assert.ok(r.frames > 0, 'some frames survive');
  assert.ok(r.frames < drive.frames.length);
  assert.ok(!r.ended);
  // what survives is right
  const i = r.frames - 1;
  assert.ok(Math.abs(r.egoX[i] - drive.frames[i].x) < 0.006);
});

test('a corrupted byte is reported, not thrown', () => {
  const drive = syntheticDrive({ seconds: 10 });
  const body = 16 + new DataView(drive.bytes.buffer).getUint32(12, true);
  for (const at of [0.01, 0.3, 0.7, 0.999]) {
    const bad = drive.bytes.slice();
    const k = body + Math.floor((bad.length - body) * at);
    bad[k] ^= 0x5a;
    const r = decodeReplay(bad, 'bad.otr');
    assert.ok(r.problem, `corruption at ${k} is noticed`);
    assert.match(r.problem, /bad\.otr/);
  }
  const inHeader = drive.bytes.slice();
  inHeader[16] = 0x78; // the header's opening brace becomes 'x'
  assert.throws(() => decodeReplay(inHeader, 'h.otr'), /h\.otr: the header is not JSON/);
});

test('missing end record is a warning', () => {
  const drive = syntheticDrive({ seconds: 2, end: false });
  const r = decodeReplay(drive.bytes);
  assert.equal(r.frames, 100);
  assert.match(r.problem, /no end record/);
});

test('bad magic, version and header throw ReplayError', () => {
  const drive = syntheticDrive({ seconds: 1 });
  const b1 = drive.bytes.slice();
  b1[0] = 0x58;
  assert.throws(() => decodeReplay(b1), ReplayError);
  const b2 = drive.bytes.slice();
  b2[8] = 9;
  assert.throws(() => decodeReplay(b2), /version 9/);
  assert.throws(() => decodeReplay(drive.bytes.subarray(0, 40)), /truncated/);
  assert.throws(() => decodeReplay(new Uint8Array(3)), /too short/);
  assert.throws(() => parseHeader('{nope'), /not JSON/);
});

test('unknown record kinds are skipped', () => {
  const drive = syntheticDrive({ seconds: 1, end: false });
  const odd = new Uint8Array([99, 3, 0, 0, 0, 1, 2, 3]);
  const bytes = encodeReplay(drive.header, [drive.records[0], odd, drive.records[1], drive.records[2]]);
  const r = decodeReplay(bytes);
  assert.equal(r.frames, 2);
  assert.equal(r.paths, 1);
});

test('live: records split across messages are joined', () => {
  const drive = syntheticDrive({ seconds: 1, end: false });
  const all = concat(drive.records);
  const r = new Replay(drive.header);
  let at = 0;
  for (const size of [7, 300, 1, 1000, 53]) {
    r.appendRecords(all.subarray(at, at + size), { live: true });
    at += size;
  }
  r.appendRecords(all.subarray(at), { live: true });
  assert.equal(r.problem, null);
  assert.equal(r.frames, 50);
  assert.equal(r.paths, 25);
});

const STILL = { step: 0, x: 0, y: 0, yaw: 0, speed: 0, s: 0, d: 0, accT: 0, accN: 0, accTotal: 0, jerk: 0, distance: 0, distanceSince: 0, bestFree: 0, cars: [] };

test('a frame whose length does not match its car count is malformed', () => {
  const f = new RecordWriter().frame(STILL);
  f[f.length - 1] = 3; // the car count, the last byte of a frame without cars: claims three
  const r = new Replay({ step_s: 0.02 });
  r.appendRecords(f);
  assert.match(r.problem, /malformed: the ids of its 3 cars run past the end/);
  assert.equal(r.frames, 0);
});

// The value as the page holds it: the stored integer times its unit, in a Float32Array.
const m32 = (m) => Math.fround(cm(m) * 0.01);

test('positions come back exactly, with cars leaving, coming back, reordered and jumping far', () => {
  const drive = syntheticDrive({ seconds: 12, churn: true, incidents: [{ step: 300, type: 'speeding', value: 51 }] });
  const r = decodeReplay(drive.bytes, 'churn.otr');
  assert.equal(r.problem, null);
  assert.equal(r.frames, drive.frames.length);
  let entries = 0;
  let far = 0;
  for (let i = 0; i < r.frames; ++i) {
    const f = drive.frames[i];
    assert.equal(r.egoX[i], m32(f.x), `ego x at ${i}`);
    assert.equal(r.egoY[i], m32(f.y), `ego y at ${i}`);
    assert.equal(r.egoYaw[i], Math.fround(yawUnits(f.yaw) * 1e-4), `ego yaw at ${i}`);
    assert.equal(r.egoSpeed[i], Math.fround(speedUnits(f.speed) * 0.01), `ego speed at ${i}`);
    assert.equal(r.carStart[i + 1] - r.carStart[i], f.cars.length, `cars at ${i}`);
    f.cars.forEach((c, k) => {
      const j = r.carStart[i] + k;
      assert.equal(r.carId[j], c.id);
      assert.equal(r.carX[j], m32(c.x), `car ${c.id} x at ${i}`);
      assert.equal(r.carY[j], m32(c.y), `car ${c.id} y at ${i}`);
      assert.equal(r.carYaw[j], Math.fround(yawUnits(c.yaw) * 1e-4), `car ${c.id} yaw at ${i}`);
      assert.equal(r.carSpeed[j], Math.fround(speedUnits(c.speed) * 0.01), `car ${c.id} speed at ${i}`);
      entries += 1;
      if (c.id === 65535) far += 1;
    });
  }
  assert.ok(entries > 0 && far > 100, `the drive has cars (${entries}) and far jumps (${far})`);
  assert.equal(r.paths, drive.paths.length);
  drive.paths.forEach((pts, k) => {
    pts.forEach(([x, y], j) => {
      assert.equal(r.pathX[r.pathStart[k] + j], m32(x));
      assert.equal(r.pathY[r.pathStart[k] + j], m32(y));
    });
  });
  assert.equal(r.incX[0], r.egoX[300], 'the incident (absolute) is where the ego (differences) is');
});

test('every cut of a frame or path record is malformed, not thrown, and keeps what came before', () => {
  const w = new RecordWriter();
  const first = w.frame({ ...STILL, cars: [{ id: 7, x: 10, y: 20, yaw: 1, speed: 3 }] });
  const frame = w.frame({ ...STILL, step: 1, x: -2e7, y: 3e3, cars: [{ id: 7, x: 2e7, y: -20, yaw: -1, speed: 600 }, { id: 300, x: 1, y: 1, yaw: 0, speed: 0 }] });
  const path = w.path([[1e7, 0], [-1e7, 5]]);
  for (const rec of [frame, path]) {
    const n = rec.length - 5;
    for (let cut = 0; cut < n; ++cut) {
      const bad = rec.slice(0, 5 + cut);
      new DataView(bad.buffer).setUint32(1, cut, true);
      const r = new Replay({ step_s: 0.02 });
      r.appendRecords(concat([first, bad]));
      assert.match(r.problem || '', /record 2 \((frame|path)\) at byte \d+ of the data is malformed/, `cut at ${cut} of ${n}: ${r.problem}`);
      assert.equal(r.frames, 1);
      assert.equal(r.carX[0], m32(10));
    }
    const r = new Replay({ step_s: 0.02 });
    r.appendRecords(concat([first, frame, path]));
    assert.equal(r.problem, null);
    assert.equal(r.egoX[1], m32(-2e7));
    assert.equal(r.carX[r.carStart[1]], m32(2e7));
    assert.equal(r.pathX[1], m32(-1e7));
  }
});

test('a repeated car id, an id above 65535, an overlong varint and a value out of range are malformed', () => {
  const car = (id) => ({ id, x: 1, y: 2, yaw: 0, speed: 1 });
  const twice = new RecordWriter().frame({ ...STILL, cars: [car(4), car(9), car(4)] });
  let r = new Replay({ step_s: 0.02 });
  r.appendRecords(twice);
  assert.match(r.problem, /car id 4 appears twice/);
  // the marks are cleared: the same replay object reads a good frame afterwards
  r = new Replay({ step_s: 0.02 });
  r.appendRecords(twice);
  r.problem = null;
  r.appendRecords(new RecordWriter().frame({ ...STILL, cars: [car(4), car(9)] }));
  assert.equal(r.problem, null);
  assert.equal(r.carStart[1] - r.carStart[0], 2);

  const big = new RecordWriter().frame({ ...STILL, cars: [{ id: 65535, x: 0, y: 0, yaw: 0, speed: 0 }] });
  const at = big.length - 4 - 3; // the id: 3 bytes, then four 1-byte differences (zeros)
  assert.deepEqual([...big.subarray(at, at + 3)], [0xff, 0xff, 0x03]);
  big[at + 2] = 0x04; // 0x7f + 0x7f << 7 + 4 << 14 = 81919
  r = new Replay({ step_s: 0.02 });
  r.appendRecords(big);
  assert.match(r.problem, /car id 81919 is above 65535/);

  const long = new Uint8Array([1, 10, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01]); // a 6-byte varint
  r = new Replay({ step_s: 0.02 });
  r.appendRecords(long);
  assert.match(r.problem, /the ego's position and speed hold a varint longer than 5 bytes/);

  const w = new RecordWriter();
  const moving = w.frame({ ...STILL, cars: [car(1)] });
  const stopped = w.frame({ ...STILL, step: 1, speed: 0, cars: [{ ...car(1), speed: 0 }] });
  r = new Replay({ step_s: 0.02 });
  // read the second frame first: its car's speed difference (-100 cm/s) from zero is negative
  r.appendRecords(stopped);
  assert.match(r.problem, /a car's speed comes to -100, outside \[0, 65535\]/);
  r = new Replay({ step_s: 0.02 });
  r.appendRecords(concat([moving, stopped]));
  assert.equal(r.problem, null);
});

test('version 1 is refused with a clear message', () => {
  const drive = syntheticDrive({ seconds: 1 });
  const v1 = drive.bytes.slice();
  v1[8] = 1;
  assert.throws(() => decodeReplay(v1, 'old.otr'), /old\.otr is replay format version 1, which is no longer supported: re-record/);
  assert.throws(() => parseHeader(JSON.stringify({ ...drive.header, version: 1 })), /version 1 is no longer supported/);
});

test('adler32 and base64 helpers', () => {
  assert.equal(adler32(new TextEncoder().encode('Wikipedia')), 0x11e60398);
  const bytes = new Uint8Array(1000).map((_, i) => (i * 37) & 255);
  for (const n of [0, 1, 2, 3, 4, 999, 1000]) {
    const part = bytes.subarray(0, n);
    assert.deepEqual(base64ToBytes(Buffer.from(part).toString('base64')), part);
  }
  assert.deepEqual(base64ToBytes('AQID\nBA=='), new Uint8Array([1, 2, 3, 4]));
});

test('the native inflate path reads the same, and falls back on a fault', async () => {
  const drive = syntheticDrive({ seconds: 4, incidents: [{ step: 50, type: 'speeding', value: 51 }] });
  const a = decodeReplay(drive.bytes);
  const b = await decodeReplayAsync(drive.bytes);
  assert.equal(b.problem, null);
  assert.equal(b.frames, a.frames);
  assert.equal(b.incidents, 1);
  assert.deepEqual(b.egoX.subarray(0, b.frames), a.egoX.subarray(0, a.frames));
  const body = 16 + new DataView(drive.bytes.buffer).getUint32(12, true);
  const cut = await decodeReplayAsync(drive.bytes.subarray(0, body + Math.floor((drive.bytes.length - body) / 2)), 'cut.otr');
  assert.match(cut.problem, /truncated/);
  assert.ok(cut.frames > 0 && cut.frames < a.frames);
  const bad = drive.bytes.slice();
  bad[bad.length - 2] ^= 1; // inside the Adler-32
  const c = await decodeReplayAsync(bad, 'sum.otr');
  assert.match(c.problem, /checksum/);
});

test('plan statuses: a run that left normal planning says so, a clean one says nothing', async () => {
  const { planStatusText } = await import('../src/viewer/format.js');
  assert.equal(planStatusText(null), '');
  assert.equal(planStatusText({ planner_cycles: 100 }), '');  // a report from before statuses
  assert.equal(planStatusText({ planner_cycles: 100, plan_status: { cycles: { normal: 100, least_bad: 0, fallback: 0 } } }), '');
  assert.equal(
    planStatusText({ planner_cycles: 200, plan_status: { cycles: { normal: 158, least_bad: 2, fallback: 40 } } }),
    'planner: least-bad 1.0%, fallback 20.0% of cycles',
  );
});

test('TTC, headway and collision classes come back; 65535 is none', () => {
  const drive = syntheticDrive({
    seconds: 12,
    incidents: [
      { step: 120, type: 'collision', value: 5, kind: 'hit_from_behind', atFault: false },
      { step: 200, type: 'max_jerk', value: 12.5 },
      { step: 300, type: 'collision', value: 7, kind: 'ego_lane_change', atFault: true },
    ],
  });
  const r = decodeReplay(drive.bytes);
  assert.equal(r.problem, null);
  assert.deepEqual(r.collisionKinds, COLLISION_KINDS);
  assert.equal(r.safetyFrames, r.frames);
  let none = 0;
  for (let i = 0; i < r.frames; ++i) {
    const want = syntheticSafety(drive.frames[i].step);
    for (const [col, key] of [['ttcAhead', 'ttcAhead'], ['ttcEntering', 'ttcEntering'], ['headway', 'headway']]) {
      const w = centiseconds(want[key]);
      if (w === 65535) {
        assert.equal(r[col][i], Infinity, `${key} at ${i} is none`);
        none += 1;
      } else {
        assert.equal(r[col][i], Math.fround(w * 0.01), `${key} at ${i}`);
      }
    }
  }
  assert.ok(none > 0 && none < 3 * r.frames, `some figures are none (${none})`);
  assert.deepEqual(r.incidentClass(0), { kind: 'hit_from_behind', atFault: false });
  assert.equal(r.incidentClass(1), null, 'a jerk incident has no class');
  assert.deepEqual(r.incidentClass(2), { kind: 'ego_lane_change', atFault: true });
  assert.equal(r.incKind[1], NO_COLLISION_KIND);
  assert.equal(r.report.collisions.at_fault, 1);
});

test('a TTC of 655.35 s or more, or none, is stored as 65535 and read as none', () => {
  assert.equal(centiseconds(655.34), 65534);
  assert.equal(centiseconds(655.35), 65535);
  assert.equal(centiseconds(Infinity), 65535);
  assert.equal(centiseconds(null), 65535);
  const w = new RecordWriter();
  const r = new Replay({ step_s: 0.02 });
  r.appendRecords(concat([
    w.frame({ ...STILL, safety: { ttcAhead: 700, ttcEntering: 0, headway: 655.34 } }),
    w.frame({ ...STILL, step: 1, safety: { ttcAhead: 1.234, ttcEntering: null, headway: 1.5 } }),
  ]));
  assert.equal(r.problem, null);
  assert.deepEqual([r.ttcAhead[0], r.ttcEntering[0], r.headway[0]], [Infinity, 0, Math.fround(655.34)]);
  assert.deepEqual([r.ttcAhead[1], r.ttcEntering[1], r.headway[1]], [Math.fround(1.23), Infinity, 1.5]);
});

test('an older file (no collision_kinds, no TTC, 18-byte incidents) reads as before, without them', () => {
  const drive = syntheticDrive({ seconds: 6, legacy: true, incidents: [{ step: 120, type: 'collision', value: 3 }] });
  assert.equal(drive.header.collision_kinds, undefined);
  const r = decodeReplay(drive.bytes, 'old.otr');
  assert.equal(r.problem, null);
  assert.deepEqual(r.collisionKinds, []);
  assert.equal(r.frames, drive.frames.length);
  assert.equal(r.safetyFrames, 0);
  assert.equal(r.ttcAhead[10], Infinity);
  assert.equal(r.headway[r.frames - 1], Infinity);
  assert.equal(r.incidents, 1);
  assert.equal(r.incidentTypeName(r.incType[0]), 'collision');
  assert.equal(r.incidentClass(0), null);
  close(r.incValue[0], 3, 0, 'the other car');
  // the same records, each frame and incident of the newer length: the same positions
  const now = decodeReplay(syntheticDrive({ seconds: 6, incidents: [{ step: 120, type: 'collision', value: 3, kind: 'car_cut_in' }] }).bytes);
  assert.deepEqual(now.egoX.subarray(0, now.frames), r.egoX.subarray(0, r.frames));
  assert.deepEqual(now.carX.subarray(0, now.cars), r.carX.subarray(0, r.cars));
  assert.equal(now.incidentClass(0).kind, 'car_cut_in');
});

test('bytes after the known fields of a frame or incident are ignored; a cut TTC is none', () => {
  const w = new RecordWriter();
  const frame = w.frame({ ...STILL, cars: [{ id: 3, x: 1, y: 2, yaw: 0, speed: 4 }], safety: { ttcAhead: 2, ttcEntering: 3, headway: 4 } });
  const inc = incidentRecord({ type: 0, value: 3, s: 1, lane: 1, x: 0, y: 0, kind: 1, atFault: true });
  // a later writer's record: three more bytes at the end of each
  const longer = (rec) => {
    const out = new Uint8Array(rec.length + 3);
    out.set(rec);
    out.set([9, 9, 9], rec.length);
    new DataView(out.buffer).setUint32(1, rec.length - 5 + 3, true);
    return out;
  };
  let r = new Replay({ step_s: 0.02, collision_kinds: COLLISION_KINDS });
  r.appendRecords(concat([longer(frame), longer(inc)]));
  assert.equal(r.problem, null);
  assert.deepEqual([r.ttcAhead[0], r.ttcEntering[0], r.headway[0]], [2, 3, 4]);
  assert.deepEqual(r.incidentClass(0), { kind: 'hit_from_behind', atFault: true });
  assert.equal(r.carSpeed[0], 4);
  // a frame cut inside its TTC and headway (fewer than six bytes of them) has none, as an
  // older one; its cars are whole
  for (let cut = 1; cut <= 6; ++cut) {
    const bad = frame.slice(0, frame.length - cut);
    new DataView(bad.buffer).setUint32(1, bad.length - 5, true);
    r = new Replay({ step_s: 0.02 });
    r.appendRecords(bad);
    assert.equal(r.problem, null, `cut ${cut}`);
    assert.equal(r.ttcAhead[0], Infinity);
    assert.equal(r.carSpeed[0], 4);
  }
  // an incident of 19 bytes: no class
  const odd = concat([inc.subarray(0, 5), inc.subarray(5, 5 + 19)]);
  new DataView(odd.buffer).setUint32(1, 19, true);
  r = new Replay({ step_s: 0.02, collision_kinds: COLLISION_KINDS });
  r.appendRecords(concat([frame, odd]));
  assert.equal(r.problem, null);
  assert.equal(r.incidentClass(0), null);
});

test('an incident shorter than 18 bytes, a collision kind beyond collision_kinds, or at fault above 1 is malformed', () => {
  const w = new RecordWriter();
  const frame = w.frame(STILL);
  const inc = (over) => incidentRecord({ type: 0, value: 3, s: 1, lane: 1, x: 0, y: 0, kind: 0, atFault: false, ...over });
  const read = (header, ...records) => {
    const r = new Replay({ step_s: 0.02, ...header });
    r.appendRecords(concat([frame, ...records]));
    return r;
  };
  let r = read({ collision_kinds: COLLISION_KINDS }, inc({ kind: 8 }));
  assert.match(r.problem, /record 2 \(incident\) at byte \d+ of the data is malformed: collision kind 8 is not one of the header's 8 collision_kinds/);
  assert.equal(r.incidents, 0);
  assert.equal(r.frames, 1);
  // a file without collision_kinds has no kind to name
  r = read({}, inc({ kind: 0 }));
  assert.match(r.problem, /collision kind 0 is not one of the header's 0 collision_kinds/);
  const fault = inc({ kind: 2 });
  fault[fault.length - 1] = 2;
  r = read({ collision_kinds: COLLISION_KINDS }, fault);
  assert.match(r.problem, /record 2 \(incident\) .* is malformed: its at-fault byte is 2, not 0 or 1/);
  // 255: not a collision, whatever its fault byte
  const none = inc({ kind: 255 });
  none[none.length - 1] = 7;
  r = read({ collision_kinds: COLLISION_KINDS }, none);
  assert.equal(r.problem, null);
  assert.equal(r.incidentClass(0), null);
  const short = concat([inc().subarray(0, 5), inc().subarray(5, 5 + 17)]);
  new DataView(short.buffer).setUint32(1, 17, true);
  r = read({ collision_kinds: COLLISION_KINDS }, short);
  assert.match(r.problem, /malformed: an incident needs 18 bytes, has 17/);
});

test('contacts: a collision incident\'s contact number comes back, 0-based; latched repeats share it', () => {
  const drive = syntheticDrive({
    seconds: 30,
    incidents: [
      { step: 400, type: 'collision', value: 4, kind: 'hit_from_behind' },
      { step: 450, type: 'collision', value: 4, kind: 'hit_from_behind' }, // the same contact, a second on
      { step: 500, type: 'collision', value: 4, kind: 'hit_from_behind' },
      { step: 900, type: 'max_jerk', value: 14.2 },
      { step: 1000, type: 'collision', value: 9 }, // unclassified: no contact
      { step: 1200, type: 'collision', value: 6, kind: 'ego_lane_change', atFault: true },
      { step: 1230, type: 'collision', value: 4, kind: 'car_cut_in' }, // car 4 again, later: a contact of its own
    ],
  });
  const r = decodeReplay(drive.bytes);
  assert.equal(r.problem, null);
  assert.equal(r.incidents, 7);
  assert.deepEqual(Array.from(r.incContact.subarray(0, r.incidents)), [0, 0, 0, -1, -1, 1, 2]);
  assert.deepEqual([0, 3, 5, 6, 7, -1].map((k) => r.incidentContact(k)), [0, -1, 1, 2, -1, -1]);
  const { list, repeat, byNumber } = r.contacts();
  assert.deepEqual(list, [{ contact: 0, first: 0, incidents: 3 }, { contact: 1, first: 5, incidents: 1 }, { contact: 2, first: 6, incidents: 1 }]);
  assert.deepEqual(Array.from(repeat), [0, 1, 1, 0, 0, 0, 0]);
  assert.equal(byNumber.get(2).first, 6);
  // the end record's report: contacts, and the rubric's latched count beside them
  const c = r.report.collisions;
  assert.equal(c.total, 3);
  assert.equal(c.at_fault, 1);
  assert.equal(c.rubric_incidents, 6);
  assert.deepEqual(c.contacts.map((x) => [x.car, x.rubric_incidents, x.kind]), [[4, 3, 'hit_from_behind'], [6, 1, 'ego_lane_change'], [4, 1, 'car_cut_in']]);
  assert.deepEqual(r.report.incidents.map((i) => i.contact), [0, 0, 0, undefined, undefined, 1, 2]);
});

test('a contact number on an incident of another type than collision is refused', () => {
  const w = new RecordWriter();
  const frame = w.frame(STILL);
  const r = new Replay({ step_s: 0.02, collision_kinds: COLLISION_KINDS,
                         incident_types: ['collision', 'speeding'] });
  r.appendRecords(concat([frame, incidentRecord({ type: 1, value: 23, s: 1, lane: 1, x: 0, y: 0,
                                                  kind: 0, atFault: true, contact: 2 })]));
  assert.match(r.problem, /contact number 3 on an incident that is no classified collision/);
});

test('incidents of 18, 20 and 24 bytes: no class, a class, a class and a contact; 0 is none; later bytes are ignored', () => {
  const w = new RecordWriter();
  const frame = w.frame(STILL);
  const base = { type: 0, value: 3, s: 1, lane: 1, x: 0, y: 0 };
  const read = (...records) => {
    const r = new Replay({ step_s: 0.02, collision_kinds: COLLISION_KINDS });
    r.appendRecords(concat([frame, ...records]));
    return r;
  };
  const sizes = [incidentRecord(base), incidentRecord({ ...base, kind: 1, atFault: false }), incidentRecord({ ...base, kind: 1, atFault: true, contact: 4 })]
    .map((rec) => rec.length - 5);
  assert.deepEqual(sizes, [18, 20, 24]);
  const r = read(incidentRecord(base), incidentRecord({ ...base, kind: 1, atFault: false }), incidentRecord({ ...base, kind: 3, atFault: true, contact: 4 }),
    incidentRecord({ ...base, kind: 0, atFault: true, contact: null }), incidentRecord({ ...base, type: 3, kind: 255, contact: -1 }));
  assert.equal(r.problem, null);
  assert.equal(r.incidents, 5);
  assert.deepEqual([0, 1, 2, 3, 4].map((k) => r.incidentContact(k)), [-1, -1, 4, -1, -1]);
  assert.deepEqual([0, 1, 2].map((k) => r.incidentClass(k)), [null, { kind: 'hit_from_behind', atFault: false }, { kind: 'ego_lane_change', atFault: true }]);
  // the u32 is little-endian, from 1
  const big = incidentRecord({ ...base, kind: 0, atFault: false, contact: 0x01020304 - 1 });
  assert.deepEqual(Array.from(big.subarray(5 + 20, 5 + 24)), [4, 3, 2, 1]);
  assert.equal(read(big).incidentContact(0), 0x01020304 - 1);
  const max = incidentRecord({ ...base, kind: 0, atFault: false, contact: 0xfffffffe });
  assert.equal(read(max).incidentContact(0), 0xfffffffe);
  // 21 to 23 bytes: a class and no contact; 27 (a later writer's): the contact, the rest ignored
  const sized = (rec, n) => {
    const out = new Uint8Array(5 + n);
    out.set(rec.subarray(0, Math.min(rec.length, 5 + n)));
    new DataView(out.buffer).setUint32(1, n, true);
    return out;
  };
  const full = incidentRecord({ ...base, kind: 2, atFault: false, contact: 6 });
  for (const n of [21, 22, 23]) {
    const rr = read(sized(full, n));
    assert.equal(rr.problem, null, `${n} bytes`);
    assert.equal(rr.incidentContact(0), -1, `${n} bytes: no contact`);
    assert.equal(rr.incidentClass(0).kind, 'hit_from_behind_braking');
  }
  const later = sized(full, 27);
  later.set([9, 9, 9], 5 + 24);
  assert.equal(read(later).incidentContact(0), 6);
});

test('a contact number on an incident that is no classified collision is malformed', () => {
  const w = new RecordWriter();
  const frame = w.frame(STILL);
  const r = new Replay({ step_s: 0.02, collision_kinds: COLLISION_KINDS });
  r.appendRecords(concat([frame, incidentRecord({ type: 1, value: 51, s: 1, lane: 1, x: 0, y: 0, kind: 255, contact: 2 })]));
  assert.match(r.problem, /record 2 \(incident\) at byte \d+ of the data is malformed: contact number 3 on an incident that is no classified collision/);
  assert.equal(r.incidents, 0);
  // a whole file with one: what comes before it is kept, with the problem named
  const drive = syntheticDrive({ seconds: 4, incidents: [{ step: 100, type: 'speeding', value: 51 }] });
  const records = drive.records.map((rec) => (rec[0] === 3 ? incidentRecord({ ...drive.incidents[0], kind: 255, contact: 0 }) : rec));
  const bad = decodeReplay(encodeReplay(drive.header, records), 'bad.otr');
  assert.match(bad.problem, /^bad\.otr: record \d+ \(incident\) .* malformed: contact number 1 on an incident that is no classified collision/);
  assert.equal(bad.frames, 101);
});

test('a file from before contacts (20-byte incidents, collisions without contacts) reads as before, with no contact', () => {
  const drive = syntheticDrive({ seconds: 12, preContacts: true,
    incidents: [{ step: 120, type: 'collision', value: 5, kind: 'hit_from_behind' }, { step: 170, type: 'collision', value: 5, kind: 'hit_from_behind' }] });
  assert.ok(drive.records.filter((rec) => rec[0] === 3).every((rec) => rec.length - 5 === 20));
  const r = decodeReplay(drive.bytes);
  assert.equal(r.problem, null);
  assert.deepEqual([r.incidentContact(0), r.incidentContact(1)], [-1, -1]);
  assert.equal(r.contacts().list.length, 0);
  assert.equal(r.incidentClass(1).kind, 'hit_from_behind');
  assert.equal(r.report.collisions.total, 2, 'counted per incident');
  assert.equal(r.report.collisions.contacts, undefined);
});

test('contact texts: the banner names the contact, the report counts contacts beside the rubric\'s incidents', async () => {
  const { collisionsText, incidentText, latchedText, safetyStatusText } = await import('../src/viewer/format.js');
  assert.equal(incidentText('collision', 5, { kind: 'hit_from_behind', atFault: false }, 1), 'Collision with car 5 (contact 2) — hit from behind (not at fault)');
  assert.equal(incidentText('collision', 5, null, 0), 'Collision with car 5 (contact 1)');
  assert.equal(incidentText('collision', 5, { kind: 'ego_lane_change', atFault: true }, -1), 'Collision with car 5 — ego lane change (at fault)');
  assert.equal(incidentText('speeding', 51.2, null, 3), 'Speed limit exceeded: 51.2 mph');
  assert.equal(latchedText(2, 3), 'still in contact: the rubric\'s collision incident 2 of 3 (one per second of contact; one collision)');
  const report = { collisions: { total: 3, at_fault: 2, rubric_incidents: 7, by_kind: {}, contacts: [{}, {}, {}] }, safety: { near_miss_episodes: 2 } };
  assert.equal(collisionsText(report), '3 collisions (contacts), 2 at fault; the rubric counted 7 collision incidents (one per second of contact)');
  assert.equal(safetyStatusText(report), '3 collisions (contacts), 2 at fault; the rubric counted 7 collision incidents (one per second of contact) · 2 near misses');
  assert.equal(collisionsText({ collisions: { total: 1, at_fault: 0, rubric_incidents: 1, contacts: [{}] } }),
    '1 collision (contact), 0 at fault; the rubric counted 1 collision incident (one per second of contact)');
  assert.equal(collisionsText({ collisions: { total: 0, at_fault: 0, rubric_incidents: 0, contacts: [] } }), '');
  // a report from before contacts: as before, saying so
  assert.equal(collisionsText({ collisions: { total: 2, at_fault: 1 } }), '2 collisions (1 at fault), counted before contacts (one per second of contact)');
  assert.equal(collisionsText({ collisions: { total: 1 } }), '1 collision, counted before contacts (one per second of contact)');
  assert.equal(collisionsText(null), '');
});

test('incident and status texts name the collision kind and fault', async () => {
  const { incidentText, safetyStatusText } = await import('../src/viewer/format.js');
  assert.equal(incidentText('collision', 5, { kind: 'hit_from_behind', atFault: false }), 'Collision with car 5 — hit from behind (not at fault)');
  assert.equal(incidentText('collision', 5, { kind: 'ego_lane_change', atFault: true }), 'Collision with car 5 — ego lane change (at fault)');
  assert.equal(incidentText('collision', 5), 'Collision with car 5');
  assert.equal(incidentText('collision', 5, null), 'Collision with car 5');
  assert.equal(incidentText('max_jerk', 12.5, null), 'Max jerk exceeded: 12.5 m/s³');
  assert.equal(safetyStatusText(null), '');
  assert.equal(safetyStatusText({ incidents: [] }), ''); // a report from before
  assert.equal(safetyStatusText({ collisions: { total: 2, at_fault: 1 }, safety: { near_miss_episodes: 3 } }),
    '2 collisions (1 at fault), counted before contacts (one per second of contact) · 3 near misses');
  assert.equal(safetyStatusText({ collisions: { total: 0, at_fault: 0 }, safety: { near_miss_episodes: 1 } }), '1 near miss');
  assert.equal(safetyStatusText({ collisions: { total: 1, at_fault: 0 } }), '1 collision (0 at fault), counted before contacts (one per second of contact)');
});

// The columns that two decodings of the same run must share.
const COLUMNS = ['step', 'egoX', 'egoY', 'egoYaw', 'egoSpeed', 'accTotal', 'distance', 'ttcAhead', 'headway', 'framePath'];
function sameRun(a, b) {
  assert.equal(a.frames, b.frames);
  assert.equal(a.cars, b.cars);
  assert.equal(a.paths, b.paths);
  assert.equal(a.incidents, b.incidents);
  for (const k of COLUMNS) assert.deepEqual(a[k].subarray(0, a.frames), b[k].subarray(0, b.frames), k);
  assert.deepEqual(a.carX.subarray(0, a.cars), b.carX.subarray(0, b.cars), 'carX');
  assert.deepEqual(a.pathX.subarray(0, a.pathPoints), b.pathX.subarray(0, b.pathPoints), 'pathX');
}

test('checkpoint records (kind 5) are skipped without a problem, wherever they are', async () => {
  assert.equal(RECORD.checkpoint, 5);
  const plain = syntheticDrive({ seconds: 8, incidents: [{ step: 150, type: 'collision', value: 2, kind: 'hit_from_behind' }] });
  const withCheckpoints = syntheticDrive({ seconds: 8, checkpointEvery: 100, incidents: [{ step: 150, type: 'collision', value: 2, kind: 'hit_from_behind' }] });
  const kinds = withCheckpoints.records.filter((rec) => rec[0] === 5).length;
  assert.equal(kinds, 4); // after frames 0, 100, 200, 300
  for (const r of [decodeReplay(withCheckpoints.bytes, 'cp.otr'), await decodeReplayAsync(withCheckpoints.bytes, 'cp.otr')]) {
    assert.equal(r.problem, null);
    assert.ok(r.ended);
    assert.equal(r.recordsRead, withCheckpoints.records.length);
    sameRun(r, decodeReplay(plain.bytes));
  }
  // before the first frame, between a frame and its incident, last before the end, and empty
  const recs = plain.records;
  const at = recs.findIndex((rec) => rec[0] === 3);
  const mixed = [checkpointRecord(40), ...recs.slice(0, at), checkpointRecord(0), ...recs.slice(at, -1), checkpointRecord(5000), recs[recs.length - 1]];
  const r = decodeReplay(encodeReplay(plain.header, mixed));
  assert.equal(r.problem, null);
  sameRun(r, decodeReplay(plain.bytes));
  assert.equal(r.incFrame[0], 150);
  // live: split anywhere, a checkpoint is read as a whole record and skipped
  const live = new Replay(withCheckpoints.header);
  const all = concat(withCheckpoints.records);
  for (let off = 0; off < all.length; off += 97) live.appendRecords(all.subarray(off, Math.min(all.length, off + 97)), { live: true });
  assert.equal(live.problem, null);
  sameRun(live, decodeReplay(plain.bytes));
  // a checkpoint cut short is reported by its name, with the frames before it kept
  const cp = concat(withCheckpoints.records);
  const firstCp = withCheckpoints.records.findIndex((rec) => rec[0] === 5);
  const upTo = withCheckpoints.records.slice(0, firstCp).reduce((n, rec) => n + rec.length, 0);
  const cut = new Replay(withCheckpoints.header);
  cut.appendRecords(cp.subarray(0, upTo + 50));
  assert.match(cut.problem, /\(checkpoint\) at byte \d+ of the data is cut short/);
  assert.equal(cut.frames, 1);
});

const CUT_FROM = {
  scenario: 'reference, faithful traffic, seed 5, t 1064.4 s', replay: 't2s5.otr', policy: 'reference', traffic: 'faithful', seed: 5,
  at_s: 1064.44, start_s: 1049.44, incident: 'collision hit_from_behind (not at fault) at t 1064.44 s',
};

test('a cut scenario\'s replay: cut_from is read, its frames start at a later step', () => {
  const start = Math.round(1049.44 / 0.02);
  const drive = syntheticDrive({ seconds: 20, startStep: start, cutFrom: CUT_FROM, checkpointEvery: 250,
    incidents: [{ step: 53222, type: 'collision', value: 3, kind: 'hit_from_behind' }] });
  const r = decodeReplay(drive.bytes, 'cut.otr');
  assert.equal(r.problem, null);
  assert.deepEqual(r.cutFrom, {
    scenario: CUT_FROM.scenario, replay: 't2s5.otr', policy: 'reference', traffic: 'faithful', seed: 5,
    atS: 1064.44, startS: 1049.44, incident: CUT_FROM.incident,
  });
  assert.equal(r.frames, 1000);
  assert.equal(r.step[0], start);
  close(r.time[0], 1049.44, 1e-9, 'first time');
  close(r.time[r.frames - 1], 1069.42, 1e-9, 'last time');
  assert.equal(r.frameOfStep(0), 0);
  assert.equal(r.frameOfStep(53222), 53222 - start);
  assert.equal(r.step[r.incFrame[0]], 53222);
  assert.match(r.summary(), /^1000 frames \(t 1049\.44 to 1069\.42 s\)/);
  // the moment's frame, and the command for it
  const i = r.frameOfStep(Math.round(r.cutFrom.atS / r.stepS));
  assert.equal(cutCommand('cut.otr', r.time[i]), 'overtake cut cut.otr --at 1064.44 -o cut-1064.json');
  assert.equal(decodeReplay(syntheticDrive({ seconds: 1 }).bytes).cutFrom, null);
});

test('cut_from: missing fields are empty, without a moment it is none', () => {
  const header = (c) => ({ provenance: { policy: 'x', cut_from: c } });
  assert.equal(cutOrigin(header(undefined)), null);
  assert.equal(cutOrigin({}), null);
  assert.equal(cutOrigin(null), null);
  assert.equal(cutOrigin(header(null)), null);
  assert.equal(cutOrigin(header('t2s5.otr')), null);
  assert.equal(cutOrigin(header([1064.44])), null);
  assert.equal(cutOrigin(header({ replay: 'a.otr' })), null);
  assert.equal(cutOrigin(header({ replay: 'a.otr', at_s: '1064' })), null);
  const c = cutOrigin(header({ at_s: 60, replay: 7, start_s: null }));
  assert.deepEqual(c, { scenario: '', replay: '', policy: '', traffic: '', seed: null, atS: 60, startS: NaN, incident: '' });
  assert.equal(cutOriginText(c), 'Cut at t 60.00 s');
});

test('the cut command and the cut origin\'s text', () => {
  assert.equal(cutCommand('run.otr', 1064.44), 'overtake cut run.otr --at 1064.44 -o cut-1064.json');
  assert.equal(cutCommand('run.otr', 53222 * 0.02), 'overtake cut run.otr --at 1064.44 -o cut-1064.json');
  assert.equal(cutCommand('run.otr', 1064.44, 'replayed'), 'overtake cut run.otr --at 1064.44 -o cut-1064.json --traffic replayed');
  assert.equal(cutCommand('run.otr', 1064.44, 'reactive'), 'overtake cut run.otr --at 1064.44 -o cut-1064.json');
  assert.equal(cutCommand(null, 0), `overtake cut ${REPLAY_PLACEHOLDER} --at 0.00 -o cut-0.json`);
  assert.equal(cutCommand('', 59.999), 'overtake cut REPLAY.otr --at 60.00 -o cut-60.json');
  assert.equal(cutCommand('runs/t2 s5.otr', 7.5), "overtake cut 'runs/t2 s5.otr' --at 7.50 -o cut-7.json");
  assert.equal(shellWord("it's.otr"), "'it'\\''s.otr'");
  assert.equal(shellWord('$(rm -rf).otr'), "'$(rm -rf).otr'");
  assert.equal(shellWord('a_b-c.1.otr'), 'a_b-c.1.otr');
  const c = cutOrigin({ provenance: { cut_from: CUT_FROM } });
  assert.equal(cutOriginText(c),
    'Cut from t2s5.otr at t 1064.44 s — reference, faithful traffic, seed 5: collision hit_from_behind (not at fault) at t 1064.44 s');
  assert.equal(cutOriginText({ ...c, incident: '' }), 'Cut from t2s5.otr at t 1064.44 s — reference, faithful traffic, seed 5');
  assert.equal(cutOriginText({ ...c, seed: 0 }).includes('seed 0'), true);
  assert.equal(cutOriginText(null), '');
});
