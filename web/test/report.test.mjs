// The bench report's tables (src/report/tables.js) and its own summary of runs
// (src/report/summary.js), on a bench of today and on older ones that lack keys: intervals,
// collision classes, near misses, pairs. (test/replay.test.mjs imports this file: CTest runs
// that one.)
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { summarize } from '../src/report/summary.js';
import {
  deltaCI, groupsOf, hasPrecision, pairColumns, pairsOf, precisionColumns, signed, summaryColumns, thresholdsOf, withCI,
} from '../src/report/tables.js';

// A summary row as a bench from before intervals wrote it (docs/replay.md's keys, no more).
const OLD_ROW = {
  policy: 'reference', traffic: 'faithful', runs: 2, total_miles: 0.667, mean_speed_mph: 40.037, incidents: 0,
  incidents_per_100mi: 0, incidents_per_100mi_by_type: { collision: 0, speeding: 0, max_acceleration: 0, max_jerk: 0, outside_lane: 0 },
  incident_free_miles_median: 0.334, incident_free_miles_worst: 0.331, peak_acceleration_mps2: 3.31, peak_jerk_mps3: 2.373,
  peak_strict_acceleration_mps2: 4.01, peak_strict_jerk_mps3: 40, timing: { planner_p50_us_median: 1.1, planner_p99_us_worst: 1.3 },
};

// The same with every key a bench of today adds.
const NEW_ROW = {
  ...OLD_ROW,
  policy: 'walkthrough',
  mean_speed_mph: 43.5712,
  mean_speed_mph_ci: [43.104, 44.0],
  incidents_per_100mi: 12.3,
  incidents_per_100mi_ci: [8.1, 17.9],
  incidents_per_100mi_by_type: { ...OLD_ROW.incidents_per_100mi_by_type, collision: 1.5, max_jerk: 10.8 },
  incidents_per_100mi_by_type_ci: { collision: [0.2, 5.4], speeding: [0, 0.8], max_acceleration: [0, 0.8], max_jerk: [7, 16], outside_lane: [0, 0.8] },
  incident_free_miles_median_ci: [0.3, 0.34],
  collisions: {
    total: 3, per_100mi: 1.5, per_100mi_ci: [0.3, 4.4], at_fault: 1, at_fault_per_100mi: 0.5, at_fault_per_100mi_ci: [0.01, 2.79],
    by_kind: { ego_hit_car_ahead: 1, hit_from_behind: 2, hit_from_behind_braking: 0 },
  },
  near_misses: {
    episodes: 4, per_100mi: 2, per_100mi_ci: [0.5, 5.1], min_ttc_ahead_s: 0.84, min_ttc_entering_s: null, min_time_headway_s: 0.3,
    share_ttc_below: 0.0123, share_headway_below: 0.2, ttc_threshold_s: 1.5, headway_threshold_s: 1.0,
  },
  precision: {
    mean_speed_mph: { half_width: 0.45, seeds_to_halve: 80 },
    incidents_per_100mi: { half_width: 4.9, seeds_to_halve: 76 },
    at_fault_collisions_per_100mi: null,
  },
};

const texts = (columns, item) => columns.map((c) => c.cell(item).text);

test('interval texts', () => {
  assert.equal(withCI(43.5712, [43.104, 44.0], 2, 1), '43.57 (43.1–44.0)');
  assert.equal(withCI(43.5712, null, 2, 1), '43.57');
  assert.equal(withCI(43.5712, [1], 2), '43.57');
  assert.equal(withCI(undefined, [1, 2], 2), '–');
  assert.equal(withCI(null, [1, 2], 2), '–');
  assert.equal(signed(-0.004, 2), '0.00');
  assert.equal(signed(1.2, 1), '+1.2');
  assert.equal(deltaCI(-1.25, [-2, -0.5], 2), '−1.25 (−2.00 to −0.50)');
  assert.equal(deltaCI(1.5, [-0.3, 3.1], 1), '+1.5 (−0.3 to +3.1)');
  assert.equal(deltaCI(undefined, [1, 2], 1), '–');
});

test('the summary shows intervals, at-fault collisions and near misses of a bench of today', () => {
  const cols = summaryColumns([NEW_ROW]);
  const row = Object.fromEntries(cols.map((c) => [`${c.group}|${c.label}`, c.cell(NEW_ROW)]));
  assert.equal(row['speed|mean mph (95% CI)'].text, '43.57 (43.1–44.0)');
  assert.equal(row['incidents per 100 mi|all (95% CI)'].text, '12.3 (8.1–17.9)');
  assert.equal(row['incidents per 100 mi|collision'].title, '95% interval 0.2–5.4');
  assert.equal(row['collisions per 100 mi|at fault (95% CI)'].text, '0.50 (0.01–2.79)');
  assert.match(row['collisions per 100 mi|at fault (95% CI)'].title, /1 of 3 collisions at fault; by kind: ego hit car ahead 1, hit from behind 2$/);
  assert.equal(row['near misses|per 100 mi (95% CI)'].text, '2.0 (0.5–5.1)');
  assert.equal(row['near misses|least TTC ahead (s)'].text, '0.84');
  assert.equal(row['near misses|TTC < 1.5 s'].text, '1.23%');
  assert.equal(row['near misses|headway < 1 s'].text, '20.00%');
  assert.equal(row['incident-free mi|median (95% CI) / worst'].text, '0.33 (0.30–0.34) / 0.33');
  assert.deepEqual(thresholdsOf([OLD_ROW, NEW_ROW]), { ttc: 1.5, headway: 1.0 });
  assert.deepEqual(groupsOf(cols).map((g) => g.span).reduce((a, b) => a + b, 0), cols.length);
  assert.ok(hasPrecision([OLD_ROW, NEW_ROW]));
  assert.deepEqual(texts(precisionColumns(), NEW_ROW), ['walkthrough', 'faithful', '2', '± 0.45', '80', '± 4.9', '76', '–', '–']);
});

test('an older bench: no key it lacks breaks a table, a missing figure is a dash', () => {
  for (const row of [OLD_ROW, {}, { policy: 'x', collisions: null, near_misses: null, precision: null, timing: null },
    { ...NEW_ROW, collisions: { total: 2 }, near_misses: {}, mean_speed_mph_ci: [null, 3], incidents_per_100mi_by_type_ci: null }]) {
    const t = texts(summaryColumns([row]), row);
    assert.ok(t.every((s) => typeof s === 'string' && !/undefined|NaN|null|object/.test(s)), t.join(' | '));
    const p = texts(precisionColumns(), row);
    assert.ok(p.every((s) => typeof s === 'string' && !/undefined|NaN|null/.test(s)), p.join(' | '));
  }
  const t = texts(summaryColumns([OLD_ROW]), OLD_ROW);
  assert.equal(t[4], '40.04', 'a mean speed without its interval');
  assert.ok(t.includes('–'));
  assert.ok(!hasPrecision([OLD_ROW]));
  assert.deepEqual(pairsOf({}), []);
  assert.deepEqual(pairsOf({ pairs: null }), []);
  assert.deepEqual(pairsOf({ pairs: [null, 3, { policy: 'a' }] }), [{ policy: 'a' }]);
});

const figure = (candidate, base, ci, p, verdict) => ({ candidate, base, difference: candidate - base, ci, probability_of_improvement: p, verdict });

test('paired comparisons: differences with intervals, P(A better), verdicts; missing figures are left out or dashed', () => {
  const pairs = [
    { traffic: 'faithful', policy: 'A', versus: 'B', seeds: 20, figures: {
      mean_speed_mph: figure(44.5, 43.0, [0.9, 2.01], 0.95, 'better'),
      incidents_per_100mi: figure(10, 12, [-5, 1], 0.6, 'no difference'),
      collisions_per_100mi: figure(1, 1, [-1, 1], 0.5, 'no difference'),
      at_fault_collisions_per_100mi: figure(2, 0.5, [0.2, 3], 0.1, 'worse'),
      near_misses_per_100mi: null,
    } },
    { traffic: 'dense', policy: 'A', versus: 'B', seeds: 2, figures: { mean_speed_mph: figure(40, 41, [-2, 0.1], 0.3, 'no difference') } },
  ];
  const cols = pairColumns(pairs);
  const labels = cols.map((c) => `${c.group}|${c.label}`);
  assert.ok(!labels.some((l) => l.startsWith('Δ near misses')), 'no pair has near misses');
  assert.ok(labels.includes('Δ collisions /100 mi|verdict'));
  const row = Object.fromEntries(cols.map((c) => [`${c.group}|${c.label}`, c.cell(pairs[0])]));
  assert.equal(row['|A vs B'].text, 'A vs B');
  assert.equal(row['Δ mean mph|A − B (95% CI)'].text, '+1.50 (+0.90 to +2.01)');
  assert.equal(row['Δ mean mph|A − B (95% CI)'].cls, 'num better');
  assert.equal(row['Δ mean mph|A − B (95% CI)'].title, 'A: 44.50, B: 43.00');
  assert.equal(row['Δ mean mph|P(A better)'].text, '0.95');
  assert.equal(row['Δ mean mph|verdict'].cls, 'verdict better');
  assert.equal(row['Δ incidents /100 mi|verdict'].text, 'no difference');
  assert.equal(row['Δ incidents /100 mi|verdict'].cls, 'verdict');
  assert.equal(row['Δ at-fault collisions /100 mi|A − B (95% CI)'].cls, 'num worse');
  const dense = texts(cols, pairs[1]);
  assert.ok(dense.every((s) => typeof s === 'string' && !/undefined|NaN|null/.test(s)), dense.join(' | '));
  assert.equal(dense.filter((s) => s === '–').length, 9, 'three figures the older pair lacks');
  // a pair without figures at all
  assert.ok(texts(pairColumns([{}]), {}).every((s) => typeof s === 'string'));
});

// A run's report as runs.jsonl holds it (the keys the summary reads).
function run(policy, seed, { collisions, safety } = {}) {
  return {
    config: { policy, traffic: 'faithful', seed }, distance_miles: 10, duration_s: 900, best_incident_free_miles: 5,
    incident_counts: { collision: collisions ? collisions.total : 1, speeding: 0, max_acceleration: 0, max_jerk: 2, outside_lane: 0 },
    peak: {}, timing: { p50_us: 3, p99_us: 9 },
    ...(collisions ? { collisions } : {}), ...(safety ? { safety } : {}),
  };
}
const SAFETY = (ttc, episodes) => ({
  min_ttc_ahead_s: ttc, min_ttc_entering_s: null, min_time_headway_s: 0.5, time_ttc_below_s: 9, share_ttc_below: 0.01,
  time_headway_below_s: 90, share_headway_below: 0.1, near_miss_episodes: episodes, ttc_threshold_s: 1.5, headway_threshold_s: 1.0,
});

test('the page\'s own summary counts collisions at fault and near misses when every run has them', () => {
  const classified = { total: 2, at_fault: 1, by_kind: { ego_hit_car_ahead: 1, hit_from_behind: 1 } };
  const rows = summarize([
    run('A', 1, { collisions: classified, safety: SAFETY(0.9, 1) }),
    run('A', 2, { collisions: { ...classified, at_fault: 0, by_kind: { hit_from_behind: 2 } }, safety: SAFETY(null, 2) }),
    run('B', 1),
    run('B', 2, { collisions: classified, safety: SAFETY(1, 0) }),
  ], ['A', 'B'], ['faithful']);
  assert.equal(rows.length, 2);
  const [a, b] = rows;
  assert.deepEqual(a.collisions, {
    total: 4, per_100mi: 20, per_100mi_ci: null, at_fault: 1, at_fault_per_100mi: 5, at_fault_per_100mi_ci: null,
    by_kind: { ego_hit_car_ahead: 1, hit_from_behind: 3 },
  });
  assert.equal(a.near_misses.episodes, 3);
  assert.equal(a.near_misses.per_100mi, 15);
  assert.equal(a.near_misses.min_ttc_ahead_s, 0.9);
  assert.equal(a.near_misses.min_ttc_entering_s, null);
  assert.equal(a.near_misses.share_ttc_below, 0.01);
  assert.equal(b.collisions.at_fault, null, 'one of B\'s runs is from before collisions were classified');
  assert.equal(b.collisions.total, 3);
  assert.equal(b.near_misses, null);
  for (const r of rows) {
    const t = texts(summaryColumns(rows), r);
    assert.ok(t.every((s) => !/undefined|NaN|null/.test(s)), t.join(' | '));
  }
  const t = Object.fromEntries(summaryColumns(rows).map((c) => [`${c.group}|${c.label}`, c.cell(a).text]));
  assert.equal(t['collisions per 100 mi|at fault (95% CI)'], '5.00');
  assert.equal(t['near misses|per 100 mi (95% CI)'], '15.0');
  assert.equal(t['near misses|least TTC ahead (s)'], '0.90');
  assert.equal(summaryColumns(rows).find((c) => c.group === 'collisions per 100 mi').cell(b).text, '–');
  // runs with nothing at all do not break it either
  assert.equal(summarize([{}]).length, 1);
});
