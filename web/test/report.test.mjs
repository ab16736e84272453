// The bench report's tables (src/report/tables.js), its charts' layout (src/report/layout.js)
// and its own summary of runs (src/report/summary.js), on a bench of today and on older ones
// that lack keys: intervals, collision classes, contacts, tests, near misses, pairs. (CTest
// runs this file beside test/replay.test.mjs.)
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { logTicks, niceTicks, overlapping, paretoOf, placeLabels, riskPointOf, scatterLayout, slotLabels, speedSafetyOf } from '../src/report/layout.js';
import { summarize } from '../src/report/summary.js';
import {
  collisionsNote, deltaCI, groupsOf, hasPrecision, intervalMethodText, matrixCell, matrixColumns, matrixPolicies, mirrorFigure,
  PAIR_FIGURES, pairColumns, pairFigure, pairsOf, pairTraffic, precisionColumns, pValue, rateWithCI, rowNotes, signed, summaryColumns,
  thresholdsOf, verdictMethodText, withCI,
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
    by_kind: { ego_hit_car_ahead: 1, hit_from_behind: 2, hit_from_behind_braking: 0 }, rubric_incidents: 7, rubric_per_100mi: 3.5,
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
  intervals: null,
  warnings: [],
};

// A row of a bench that had too few seeds for intervals: every interval and precision null.
const FEW_ROW = {
  ...NEW_ROW, policy: 'few', runs: 3, intervals: 'too few seeds: 3, need at least 8',
  mean_speed_mph_ci: null, incidents_per_100mi_ci: null, incident_free_miles_median_ci: null,
  incidents_per_100mi_by_type_ci: { collision: null, speeding: null, max_acceleration: null, max_jerk: null, outside_lane: null },
  collisions: { ...NEW_ROW.collisions, per_100mi_ci: null, at_fault_per_100mi_ci: null },
  near_misses: { ...NEW_ROW.near_misses, per_100mi_ci: null },
  precision: { mean_speed_mph: null, incidents_per_100mi: null, at_fault_collisions_per_100mi: null },
};

// A row with no event of some rates: their intervals are [0, the one-sided upper bound].
const ZERO_ROW = {
  ...NEW_ROW, policy: 'careful', incidents_per_100mi: 0, incidents_per_100mi_ci: [0, 0.6812],
  collisions: { ...NEW_ROW.collisions, total: 0, per_100mi: 0, per_100mi_ci: [0, 0.6812], at_fault: 0, at_fault_per_100mi: 0, at_fault_per_100mi_ci: [0, 0.6812], rubric_incidents: 0, rubric_per_100mi: 0 },
  warnings: ['at_fault_collisions_per_100mi: one seed holds 100% of the events; the interval cannot tell how rare such seeds are'],
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

const cellsOf = (row, rows = [row]) => Object.fromEntries(summaryColumns(rows).map((c) => [`${c.group}|${c.label}`, c.cell(row)]));

test('the summary shows intervals, collisions as contacts, at fault and near misses of a bench of today', () => {
  const cols = summaryColumns([NEW_ROW]);
  const row = cellsOf(NEW_ROW);
  assert.equal(row['speed|mean mph (95% CI)'].text, '43.57 (43.1–44.0)');
  assert.equal(row['incidents per 100 mi|all (95% CI)'].text, '12.3 (8.1–17.9)');
  assert.equal(row['incidents per 100 mi|collision'].title, '95% interval 0.2–5.4');
  assert.equal(row['collisions (contacts) per 100 mi|all (95% CI)'].text, '1.50 (0.30–4.40)');
  assert.match(row['collisions (contacts) per 100 mi|all (95% CI)'].title, /^3 contacts \(one per car touched, however long\); the rubric counted 7 collision incidents \(one per second of contact\), 3\.50 per 100 mi$/);
  assert.equal(row['collisions (contacts) per 100 mi|at fault (95% CI)'].text, '0.50 (0.01–2.79)');
  assert.match(row['collisions (contacts) per 100 mi|at fault (95% CI)'].title, /1 of 3 contacts at fault; by kind: ego hit car ahead 1, hit from behind 2$/);
  assert.equal(row['near misses|per 100 mi (95% CI)'].text, '2.0 (0.5–5.1)');
  assert.equal(row['near misses|least TTC ahead (s)'].text, '0.84');
  assert.equal(row['near misses|least time gap (s)'].text, '0.30', 'the headway keys are a time gap');
  assert.equal(row['near misses|TTC < 1.5 s'].text, '1.23%');
  assert.equal(row['near misses|time gap < 1 s'].text, '20.00%');
  assert.ok(!cols.some((c) => /headway/.test(c.label)), 'no column says headway');
  assert.equal(row['incident-free mi|median (95% CI) / worst'].text, '0.33 (0.30–0.34) / 0.33');
  assert.deepEqual(thresholdsOf([OLD_ROW, NEW_ROW]), { ttc: 1.5, headway: 1.0 });
  assert.deepEqual(groupsOf(cols).map((g) => g.span).reduce((a, b) => a + b, 0), cols.length);
  assert.ok(hasPrecision([OLD_ROW, NEW_ROW]));
  assert.deepEqual(texts(precisionColumns(), NEW_ROW), ['walkthrough', 'faithful', '2', '± 0.45', '80', '± 4.9', '76', '–', '–']);
  assert.deepEqual(rowNotes(NEW_ROW), []);
  assert.equal(collisionsNote([NEW_ROW]), null);
});

test('a rate with no event shows its one-sided bound: "0.00 (≤ 0.68)"; an older bench\'s two-sided interval as it is', () => {
  assert.equal(rateWithCI(0, [0, 0.6812], 2), '0.00 (≤ 0.68)');
  assert.equal(rateWithCI(0, [0, 0.6812], 1), '0.0 (≤ 0.7)');
  assert.equal(rateWithCI(0, [0, 0.6812], 2, false), '0.00 (0.00–0.68)');
  assert.equal(rateWithCI(1.5, [0.3, 4.4], 2), '1.50 (0.30–4.40)');
  assert.equal(rateWithCI(1.5, [0, 4.4], 2), '1.50 (0.00–4.40)', 'a rate with events whose interval starts at 0 is two-sided');
  assert.equal(rateWithCI(0, null, 2), '0.00');
  assert.equal(rateWithCI(null, [0, 1], 2), '–');
  const row = cellsOf(ZERO_ROW);
  assert.equal(row['incidents per 100 mi|all (95% CI)'].text, '0.0 (≤ 0.7)');
  assert.equal(row['collisions (contacts) per 100 mi|all (95% CI)'].text, '0.00 (≤ 0.68)');
  assert.equal(row['collisions (contacts) per 100 mi|at fault (95% CI)'].text, '0.00 (≤ 0.68)');
  assert.equal(row['collisions (contacts) per 100 mi|at fault (95% CI)'].cls, 'num', 'no event is not bad');
  const zeroType = { ...ZERO_ROW, incidents_per_100mi_by_type: { ...ZERO_ROW.incidents_per_100mi_by_type, collision: 0 },
    incidents_per_100mi_by_type_ci: { ...ZERO_ROW.incidents_per_100mi_by_type_ci, collision: [0, 0.6812] } };
  assert.equal(cellsOf(zeroType)['incidents per 100 mi|collision'].title, 'no event: one-sided 95% upper bound 0.7');
  // the same row from an older bench (no `intervals` key): its interval of no event was two-sided
  const older = { ...ZERO_ROW };
  delete older.intervals;
  delete older.warnings;
  assert.equal(cellsOf(older)['collisions (contacts) per 100 mi|at fault (95% CI)'].text, '0.00 (0.00–0.68)');
  assert.deepEqual(rowNotes(ZERO_ROW), ['⚠ at_fault_collisions_per_100mi: one seed holds 100% of the events; the interval cannot tell how rare such seeds are']);
});

test('too few seeds: no interval anywhere, the row says why, precision is dashes (and not shown when no row has any)', () => {
  const row = cellsOf(FEW_ROW);
  assert.equal(row['speed|mean mph (95% CI)'].text, '43.57');
  assert.equal(row['incidents per 100 mi|all (95% CI)'].text, '12.3');
  assert.equal(row['incidents per 100 mi|collision'].title, undefined);
  assert.equal(row['collisions (contacts) per 100 mi|at fault (95% CI)'].text, '0.50');
  assert.equal(row['near misses|per 100 mi (95% CI)'].text, '2.0');
  assert.equal(row['incident-free mi|median (95% CI) / worst'].text, '0.33 / 0.33');
  assert.deepEqual(rowNotes(FEW_ROW), ['no intervals: too few seeds: 3, need at least 8']);
  assert.deepEqual(texts(precisionColumns(), FEW_ROW), ['few', 'faithful', '3', '–', '–', '–', '–', '–', '–']);
  assert.ok(!hasPrecision([FEW_ROW]), 'precision of nothing');
  assert.ok(hasPrecision([FEW_ROW, NEW_ROW]));
  const t = texts(summaryColumns([FEW_ROW]), FEW_ROW);
  assert.ok(t.every((x) => typeof x === 'string' && !/undefined|NaN|null|object/.test(x)), t.join(' | '));
  // warnings and the reason together, each a line
  assert.deepEqual(rowNotes({ ...FEW_ROW, warnings: ['a', 3, ''] }), ['no intervals: too few seeds: 3, need at least 8', '⚠ a']);
});

test('collisions from before contacts: none in a row of today (a dash, said once), counted per second in an older bench', () => {
  const none = { ...NEW_ROW, policy: 'old-runs', collisions: null };
  const row = cellsOf(none, [NEW_ROW, none]);
  assert.equal(row['collisions (contacts) per 100 mi|all (95% CI)'].text, '–');
  assert.equal(row['collisions (contacts) per 100 mi|at fault (95% CI)'].text, '–');
  assert.match(row['collisions (contacts) per 100 mi|at fault (95% CI)'].title, /before collisions were counted as contacts/);
  assert.equal(collisionsNote([NEW_ROW, none]), 'No collision figures (old-runs / faithful): runs from before collisions were counted as contacts (bench again to compare collisions).');
  // an older bench's row: collisions without the rubric's count, counted for every second of contact
  const older = { ...OLD_ROW, collisions: { total: 4, per_100mi: 2, per_100mi_ci: [0.5, 5.1], at_fault: 2, at_fault_per_100mi: 1, at_fault_per_100mi_ci: [0.1, 3.6], by_kind: { ego_hit_car_ahead: 2 } } };
  const old = cellsOf(older);
  assert.ok(!('collisions (contacts) per 100 mi|all (95% CI)' in old), 'an older bench\'s collisions are not called contacts');
  assert.equal(old['collisions per 100 mi|all (95% CI)'].text, '2.00 (0.50–5.10)');
  assert.equal(old['collisions per 100 mi|at fault (95% CI)'].text, '1.00 (0.10–3.60)');
  assert.match(old['collisions per 100 mi|at fault (95% CI)'].title, /2 of 4 collisions at fault; by kind: ego hit car ahead 2; counted for every second of contact/);
  assert.equal(collisionsNote([older]), 'Collisions (every row): counted for every second of contact (a bench from before collisions were counted as contacts).');
  assert.deepEqual(rowNotes(older), []);
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

test('an older bench\'s paired comparisons: differences with intervals, P(A better), verdicts; missing figures are left out or dashed', () => {
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
  assert.equal(row['Δ mean mph|P(A better) (95% CI)'].text, '0.95');
  assert.ok(!labels.some((l) => l.endsWith('|p (Holm)')), 'no p-values in an older bench');
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

// A pair's figure as a bench of today writes it.
const tested = (candidate, base, ci, p, pci, pValueRaw, pAdjusted, verdict) => ({
  candidate, base, difference: candidate - base, ci, p_value: pValueRaw, p_adjusted: pAdjusted,
  probability_of_improvement: p, probability_of_improvement_ci: pci, verdict,
});
const TODAY_PAIRS = [
  { traffic: 'faithful', policy: 'A', versus: 'B', seeds: 10, figures: {
    mean_speed_mph: tested(45.64, 38.57, [4.35, 9.79], 0.98, [0.88, 1], 8.9e-5, 0.0133, 'better'),
    incidents_per_100mi: tested(0, 0, [-11.48, 9.7], 0.5, [0.5, 0.5], null, null, 'no difference'),
    collisions_per_100mi: tested(0, 21.24, [-52.04, -3.43], 0.75, [0.6, 0.9], 0.002, 0.2, 'no difference'),
    at_fault_collisions_per_100mi: tested(21.24, 0, [3.43, 52.04], 0.25, [0.1, 0.4], 1e-4, 0.01, 'worse'),
    near_misses_per_100mi: null,
  } },
  { traffic: 'faithful', policy: 'A', versus: 'C', seeds: 10, figures: { mean_speed_mph: tested(45.64, 45.2, [-1, 2], 0.6, [0.3, 0.8], 0.4, 1, 'no difference') } },
  { traffic: 'calm', policy: 'B', versus: 'A', seeds: 3, figures: {
    mean_speed_mph: { candidate: 40, base: 41, difference: -1, ci: null, p_value: null, p_adjusted: null, probability_of_improvement: null, probability_of_improvement_ci: null, verdict: 'too few seeds' },
  } },
];
const VERDICTS_OBJECT = {
  alpha: 0.05, correction: 'Holm', family_tests: 156, min_seeds: 8, mean_test: "paired t-test on the seeds' linearized differences",
  rate_test: 'exact sign-flip randomization test over seeds', mean_interval: 'symmetric bootstrap-t over seeds',
  rate_interval: 'exact (Garwood) interval on the events over the seeds\' dispersion (quasi-Poisson, t-scaled); no event: one-sided upper bound',
  difference_interval: "means: paired symmetric bootstrap-t; rates: MOVER from both rates' intervals",
};

test('paired comparisons of today: P(A better) with its interval, the p-value after Holm, too few seeds; how the verdicts were reached', () => {
  const cols = pairColumns(TODAY_PAIRS);
  const row = Object.fromEntries(cols.map((c) => [`${c.group}|${c.label}`, c.cell(TODAY_PAIRS[0])]));
  assert.equal(row['Δ mean mph|A − B (95% CI)'].text, '+7.07 (+4.35 to +9.79)');
  assert.equal(row['Δ mean mph|P(A better) (95% CI)'].text, '0.98 (0.88–1.00)');
  assert.equal(row['Δ mean mph|p (Holm)'].text, '0.013');
  assert.equal(row['Δ mean mph|p (Holm)'].title, 'p 8.9e−5 before the correction');
  assert.equal(row['Δ incidents /100 mi|p (Holm)'].text, '–');
  assert.equal(row['Δ incidents /100 mi|p (Holm)'].title, 'not tested: the same on every seed');
  assert.equal(row['Δ at-fault collisions /100 mi|verdict'].cls, 'verdict worse');
  const few = Object.fromEntries(cols.map((c) => [`${c.group}|${c.label}`, c.cell(TODAY_PAIRS[2])]));
  assert.equal(few['Δ mean mph|A − B (95% CI)'].text, '−1.00');
  assert.equal(few['Δ mean mph|P(A better) (95% CI)'].text, '–');
  assert.equal(few['Δ mean mph|verdict'].text, 'too few seeds');
  assert.equal(few['Δ mean mph|verdict'].cls, 'verdict');
  for (const p of TODAY_PAIRS) {
    const t = texts(cols, p);
    assert.ok(t.every((x) => typeof x === 'string' && !/undefined|NaN|null/.test(x)), t.join(' | '));
  }
  assert.equal(pValue(0.0133), '0.013');
  assert.equal(pValue(1), '1.000');
  assert.equal(pValue(null), '–');
  assert.equal(verdictMethodText(VERDICTS_OBJECT),
    "Holm over 156 tests, 5% family-wise; paired t-test on the seeds' linearized differences for speed, exact sign-flip randomization test over seeds for rates; no verdict below 8 seeds");
  assert.match(intervalMethodText(VERDICTS_OBJECT), /^mean speed: symmetric bootstrap-t over seeds; rates: exact .*one-sided upper bound; differences: means: /);
  assert.equal(verdictMethodText(undefined), null);
  assert.equal(verdictMethodText({}), null);
  assert.equal(intervalMethodText(null), null);
});

test('a pair seen from the other side: the difference and its interval negated, P(improvement) complemented, the verdict mirrored', () => {
  const f = TODAY_PAIRS[0].figures.mean_speed_mph;
  const m = mirrorFigure(f);
  assert.equal(m.candidate, 38.57);
  assert.equal(m.base, 45.64);
  assert.equal(m.difference, -f.difference);
  assert.deepEqual(m.ci, [-9.79, -4.35]);
  assert.ok(Math.abs(m.probability_of_improvement - 0.02) < 1e-12);
  assert.deepEqual(m.probability_of_improvement_ci.map((x) => +x.toFixed(12)), [0, 0.12]);
  assert.equal(m.verdict, 'worse');
  assert.equal(m.p_adjusted, f.p_adjusted, 'the same test');
  assert.equal(mirrorFigure(TODAY_PAIRS[0].figures.at_fault_collisions_per_100mi).verdict, 'better');
  assert.equal(mirrorFigure(TODAY_PAIRS[0].figures.incidents_per_100mi).verdict, 'no difference');
  assert.equal(mirrorFigure(TODAY_PAIRS[0].figures.incidents_per_100mi).difference, 0);
  assert.equal(mirrorFigure(TODAY_PAIRS[2].figures.mean_speed_mph).verdict, 'too few seeds');
  assert.equal(mirrorFigure(TODAY_PAIRS[2].figures.mean_speed_mph).ci, null);
  assert.equal(mirrorFigure(null), null);
  // found either way round
  assert.equal(pairFigure(TODAY_PAIRS, 'faithful', 'A', 'B', 'mean_speed_mph').mirrored, false);
  assert.equal(pairFigure(TODAY_PAIRS, 'faithful', 'B', 'A', 'mean_speed_mph').mirrored, true);
  assert.equal(pairFigure(TODAY_PAIRS, 'faithful', 'B', 'A', 'near_misses_per_100mi').figure, null);
  assert.equal(pairFigure(TODAY_PAIRS, 'faithful', 'B', 'C', 'mean_speed_mph'), null);
  assert.equal(pairFigure(TODAY_PAIRS, 'calm', 'A', 'B', 'mean_speed_mph').mirrored, true);
});

test('the matrix of a figure: a cell per pair coloured and marked by its verdict, the mirror cell filled, the rest on hover', () => {
  const speed = PAIR_FIGURES.find((f) => f.key === 'mean_speed_mph');
  const fault = PAIR_FIGURES.find((f) => f.key === 'at_fault_collisions_per_100mi');
  assert.deepEqual(pairTraffic(TODAY_PAIRS), ['faithful', 'calm']);
  assert.deepEqual(matrixPolicies(TODAY_PAIRS, 'faithful', ['C', 'B', 'A', 'Z']), ['C', 'B', 'A']);
  assert.deepEqual(matrixPolicies(TODAY_PAIRS, 'calm'), ['B', 'A']);
  const ab = matrixCell(TODAY_PAIRS, speed, 'faithful', 'A', 'B');
  assert.equal(ab.text, '✓ +7.07');
  assert.equal(ab.cls, 'm better');
  assert.deepEqual(ab.data, { verdict: 'better', difference: String(45.64 - 38.57), mirrored: 'false' });
  assert.equal(ab.title, ['A vs B (faithful traffic, 10 seeds)', 'mean speed (mph): A 45.64, B 38.57', 'A − B: +7.07 (+4.35 to +9.79) (95% interval)',
    'P(A better): 0.98 (0.88–1.00) (95% interval)', 'p 8.9e−5, Holm-adjusted 0.013', 'verdict: A better than B', '(higher is better)'].join('\n'));
  const ba = matrixCell(TODAY_PAIRS, speed, 'faithful', 'B', 'A');
  assert.equal(ba.text, '✗ −7.07');
  assert.equal(ba.cls, 'm worse');
  assert.equal(ba.data.mirrored, 'true');
  assert.equal(ba.data.verdict, 'worse');
  assert.match(ba.title, /^B vs A \(faithful traffic, 10 seeds\)\nmean speed \(mph\): B 38\.57, A 45\.64\nB − A: −7\.07 \(−9\.79 to −4\.35\) \(95% interval\)\nP\(B better\): 0\.02 \(0\.00–0\.12\) \(95% interval\)\np 8\.9e−5, Holm-adjusted 0\.013\nverdict: B worse than A\n\(higher is better; the data has A vs B, mirrored\)$/);
  // a rate: lower is better; worse and better swap with the side
  assert.equal(matrixCell(TODAY_PAIRS, fault, 'faithful', 'A', 'B').text, '✗ +21.24');
  assert.equal(matrixCell(TODAY_PAIRS, fault, 'faithful', 'B', 'A').text, '✓ −21.24');
  assert.match(matrixCell(TODAY_PAIRS, fault, 'faithful', 'B', 'A').title, /\(lower is better; the data has A vs B, mirrored\)$/);
  // no difference, not tested; too few seeds; none; the diagonal
  const same = matrixCell(TODAY_PAIRS, PAIR_FIGURES[1], 'faithful', 'B', 'A');
  assert.equal(same.text, '= 0.0');
  assert.equal(same.cls, 'm same');
  assert.match(same.title, /not tested: the same on every seed/);
  const few = matrixCell(TODAY_PAIRS, speed, 'calm', 'A', 'B');
  assert.equal(few.text, '? +1.00');
  assert.equal(few.cls, 'm few');
  assert.match(few.title, /verdict: too few seeds/);
  assert.doesNotMatch(few.title, /P\(A better\)/);
  assert.equal(matrixCell(TODAY_PAIRS, speed, 'faithful', 'B', 'C').cls, 'm none');
  assert.equal(matrixCell(TODAY_PAIRS, PAIR_FIGURES[4], 'faithful', 'A', 'B').text, '–');
  assert.equal(matrixCell(TODAY_PAIRS, speed, 'faithful', 'A', 'A').cls, 'm self');
  // as columns over the policies: the row's name, then a cell per column
  const cols = matrixColumns(TODAY_PAIRS, speed, 'faithful', ['A', 'B', 'C']);
  assert.deepEqual(cols.map((c) => c.label), ['A \\ B', 'A', 'B', 'C']);
  assert.deepEqual(texts(cols, 'A'), ['A', '', '✓ +7.07', '= +0.44']);
  assert.deepEqual(texts(cols, 'C'), ['C', '= −0.44', '', '']);
  // long names: the columns are numbered, each row says its number, a column's title names it
  const long = ['a-policy-with-a-long-name', 'B', 'C'];
  const renamed = TODAY_PAIRS.map((p) => ({ ...p, policy: p.policy === 'A' ? long[0] : p.policy, versus: p.versus === 'A' ? long[0] : p.versus }));
  const numbered = matrixColumns(renamed, speed, 'faithful', long);
  assert.deepEqual(numbered.map((c) => c.label), ['A \\ B', '1', '2', '3']);
  assert.deepEqual(numbered.slice(1).map((c) => c.title), long);
  assert.deepEqual(texts(numbered, long[0]), ['1 a-policy-with-a-long-name', '', '✓ +7.07', '= +0.44']);
  // every cell of an older bench's pairs (no tests, no interval of P) reads too
  const older = [{ traffic: 'faithful', policy: 'A', versus: 'B', seeds: 100, figures: { mean_speed_mph: figure(44.5, 43.0, [0.9, 2.01], 0.95, 'better') } }];
  const o = matrixCell(older, speed, 'faithful', 'B', 'A');
  assert.equal(o.text, '✗ −1.50');
  assert.match(o.title, /P\(B better\): 0\.05\n/);
  assert.doesNotMatch(o.title, /Holm|undefined|NaN|null/);
});

// The measure of a label's width in the tests: about a system font's 11 px.
const measure = (t) => 6.3 * String(t).length;

// Summary rows of `n` policies on two traffic profiles, crowded: close speeds, most with no
// at-fault collision (their marks on one line at 0).
function crowdedRows(n) {
  const rows = [];
  for (const traffic of ['faithful', 'calm']) {
    for (let i = 0; i < n; ++i) {
      const rate = i % 3 === 0 ? 0.8 + i * 0.05 : 0;
      rows.push({
        ...NEW_ROW, policy: `policy-number-${i + 1}`, traffic, mean_speed_mph: 45 + (i % 4) * 0.1 + (traffic === 'calm' ? 0.2 : 0),
        mean_speed_mph_ci: [44.5, 45.8],
        collisions: { ...NEW_ROW.collisions, at_fault_per_100mi: rate, at_fault_per_100mi_ci: rate ? [rate * 0.5, rate * 2] : [0, 0.9] },
      });
    }
  }
  return rows;
}

test('speed against safety with risk estimates: hollow points, a log rate axis, rates of 0 at its left end', () => {
  const risk = [
    { label: 'reference (risk)', policy: 'walkthrough', traffic: 'faithful', mean_speed_mph: 44.9, rate_per_100mi: 0, ci95_per_100mi: [0, 0.066], upper_bound_only: true, base_miles: 4550 },
    { label: 'reference weak1 (risk)', policy: 'careful', traffic: 'faithful', mean_speed_mph: 45.5, rate_per_100mi: 0.064, ci95_per_100mi: [0.013, 0.19], upper_bound_only: false, base_miles: 6000 },
    { label: 'broken', policy: 'x', traffic: 'faithful' }, // no figures: left out
  ];
  const rows = [NEW_ROW, ZERO_ROW];
  const lay = scatterLayout(rows, { width: 700, height: 400, measure, policies: ['walkthrough', 'careful'], traffic: ['faithful'], risk });
  assert.equal(lay.x.log, true);
  assert.equal(lay.points.length, 4);
  assert.deepEqual(lay.left, [{ policy: 'broken', traffic: 'faithful' }]);
  const [a, zero, bound, weak] = lay.points;
  assert.ok(bound.risk && bound.hollow && weak.hollow && !a.hollow && !zero.hollow);
  // coloured as their policy, labelled by their own names
  assert.equal(bound.color, a.color);
  assert.equal(weak.color, zero.color);
  assert.deepEqual(lay.labels.map((l) => l && l.text), ['walkthrough', 'careful', 'reference (risk)', 'reference weak1 (risk)']);
  // log scale: equal ratios, equal distances; the axis from half the least positive figure
  const X = (v) => lay.plot.x + ((Math.log10(v) - Math.log10(lay.x.min)) / (Math.log10(lay.x.max) - Math.log10(lay.x.min))) * lay.plot.w;
  assert.ok(Math.abs(lay.x.min - 0.01 / 2) < 1e-12, `least positive 0.01 (NEW_ROW's low end): ${lay.x.min}`);
  assert.ok(Math.abs(weak.x - X(0.064)) < 1e-9);
  assert.ok(Math.abs(weak.xBar.from - X(0.013)) < 1e-9 && Math.abs(weak.xBar.to - X(0.19)) < 1e-9);
  // rates of 0 sit at the left end, their dashed bar up to the bound
  assert.ok(Math.abs(bound.x - lay.plot.x) < 1e-9 && Math.abs(zero.x - lay.plot.x) < 1e-9);
  assert.ok(bound.xBar.oneSided && Math.abs(bound.xBar.to - X(0.066)) < 1e-9);
  assert.equal(bound.yBar, null);
  // ticks: powers of ten (and 2, 5 between when few), rising, inside the axis, with texts
  assert.ok(lay.x.ticks.length >= 3);
  for (const t of lay.x.ticks) assert.ok(t.v >= lay.x.min * (1 - 1e-9) && t.v <= lay.x.max * (1 + 1e-9) && typeof t.text === 'string');
  assert.ok(lay.x.ticks.every((t, i) => i === 0 || t.v > lay.x.ticks[i - 1].v));
  assert.deepEqual(logTicks(0.004, 30).map((t) => t.text), ['0.01', '0.1', '1', '10']);
  assert.deepEqual(logTicks(0.3, 4).map((t) => t.text), ['0.5', '1', '2']);
  assert.equal(riskPointOf({ rate_per_100mi: 1 }), null);
  // one estimate a policy: no curve; two or more of one policy (a knob's points): its
  // frontier, those no other beats on both joined in order of rate (a0, slower than a1 at
  // more risk, is not on it)
  assert.equal(lay.frontiers.length, 0);
  const knob = [0.3, 0, 1.2].map((rate, i) => ({ label: `reference a${i} (risk)`, policy: 'reference', traffic: 'faithful', mean_speed_mph: 45 + i, rate_per_100mi: rate, ci95_per_100mi: [rate / 3, rate * 3 || 0.07], upper_bound_only: rate === 0, base_miles: 2000 }));
  const fr = scatterLayout(rows, { width: 700, height: 400, measure, risk: knob });
  assert.equal(fr.frontiers.length, 1);
  assert.equal(fr.frontiers[0].policy, 'reference');
  const [k0, k1, k2] = fr.points.filter((p) => p.risk);
  assert.deepEqual(fr.frontiers[0].points, [k1, k2].map((p) => ({ x: p.x, y: p.y })));
  assert.deepEqual(paretoOf([{ rate: 0, speed: 45 }, { rate: 0, speed: 45.4 }, { rate: 0.17, speed: 46.7 }, { rate: 1.7, speed: 46.5 }]), [{ rate: 0, speed: 45.4 }, { rate: 0.17, speed: 46.7 }]);
  // without risk estimates the axis stays linear from 0
  assert.equal(scatterLayout(rows, { width: 700, height: 400, measure }).x.log, false);
});

test('speed against safety: a point per row with collision figures, error bars both ways, a one-sided bar for no event', () => {
  const old = { ...OLD_ROW, policy: 'older' }; // no collision figures: left out
  const fewRow = { ...FEW_ROW, policy: 'few' }; // no intervals: a point without bars
  const rows = [NEW_ROW, ZERO_ROW, old, fewRow, { ...NEW_ROW, policy: 'none', collisions: null }];
  const lay = scatterLayout(rows, { width: 700, height: 400, measure, policies: ['walkthrough', 'careful', 'few'], traffic: ['faithful'] });
  assert.equal(lay.points.length, 3);
  assert.deepEqual(lay.left, [{ policy: 'older', traffic: 'faithful' }, { policy: 'none', traffic: 'faithful' }]);
  const [a, zero, few] = lay.points;
  assert.ok(zero.x < a.x, 'fewer at-fault collisions: further left');
  assert.ok(a.x < lay.plot.x + lay.plot.w && zero.x > lay.plot.x, 'inside the plot, 0 clear of the axis');
  assert.ok(zero.y > a.y === (ZERO_ROW.mean_speed_mph < NEW_ROW.mean_speed_mph) || zero.y === a.y);
  // both bars of a, around it; the speed's up and down, the rate's across
  assert.ok(a.xBar && a.yBar);
  assert.ok(a.xBar.from < a.x && a.x < a.xBar.to && a.xBar.y === a.y && !a.xBar.oneSided);
  assert.ok(a.yBar.to < a.y && a.y < a.yBar.from && a.yBar.x === a.x);
  // its ends are the interval's: at-fault 0.01–2.79 per 100 mi, 43.104–44.0 mph
  const X = (v) => lay.plot.x + ((v - lay.x.min) / (lay.x.max - lay.x.min)) * lay.plot.w;
  const Y = (v) => lay.plot.y + lay.plot.h - ((v - lay.y.min) / (lay.y.max - lay.y.min)) * lay.plot.h;
  assert.ok(Math.abs(a.xBar.from - X(0.01)) < 1e-9 && Math.abs(a.xBar.to - X(2.79)) < 1e-9);
  assert.ok(Math.abs(a.yBar.from - Y(43.104)) < 1e-9 && Math.abs(a.yBar.to - Y(44.0)) < 1e-9);
  // no event: a one-sided bar from 0 (the mark) to the bound
  assert.ok(zero.xBar.oneSided);
  assert.equal(zero.xBar.from, zero.x);
  assert.ok(Math.abs(zero.xBar.to - X(0.6812)) < 1e-9);
  assert.equal(few.xBar, null);
  assert.equal(few.yBar, null);
  assert.ok(lay.x.ticks[0].v === 0 && lay.x.ticks.every((t, i) => i === 0 || t.v > lay.x.ticks[i - 1].v));
  assert.equal(lay.unplaced, 0);
  assert.equal(lay.mode, 'names');
  assert.deepEqual(lay.labels.map((l) => l.text), ['walkthrough', 'careful', 'few']);
  // an older bench's zero-event interval is two-sided: a bar with both caps
  const olderZero = { ...ZERO_ROW };
  delete olderZero.intervals;
  assert.equal(speedSafetyOf(olderZero).oneSided, false);
  assert.equal(speedSafetyOf(ZERO_ROW).oneSided, true);
  assert.equal(speedSafetyOf(OLD_ROW), null);
  assert.equal(speedSafetyOf(null), null);
  // nothing to show
  const empty = scatterLayout([], { width: 300, height: 200, measure });
  assert.equal(empty.points.length, 0);
  assert.equal(empty.unplaced, 0);
});

test('labels do not overlap with eight policies and more: by name while they fit, else numbered with a legend', () => {
  for (const n of [8, 9, 12]) {
    const rows = crowdedRows(n);
    const lay = scatterLayout(rows, { width: 1300, height: 400, measure, traffic: ['faithful', 'calm'] });
    assert.equal(lay.points.length, 2 * n);
    assert.equal(lay.unplaced, 0, `${n} policies: every label placed`);
    assert.deepEqual(overlapping(lay.labels), [], `${n} policies: no two labels overlap`);
    assert.ok(lay.labels.every((l) => l.x >= lay.plot.x && l.x + l.w <= lay.plot.x + lay.plot.w && l.y >= lay.plot.y && l.y + l.h <= lay.plot.y + lay.plot.h));
    assert.deepEqual(new Set(lay.points.map((p) => p.shape)).size, 2, 'a shape per traffic profile');
    assert.deepEqual(lay.traffic, ['faithful', 'calm']);
    assert.equal(lay.policies.length, n);
  }
  // a small chart: the names cannot all be placed apart, numbers can
  const small = scatterLayout(crowdedRows(10), { width: 420, height: 260, measure });
  assert.equal(small.mode, 'numbers');
  assert.equal(small.unplaced, 0);
  assert.deepEqual(overlapping(small.labels), []);
  assert.deepEqual(small.labels.map((l) => l.text), small.points.map((_, i) => String(i + 1)));
  assert.deepEqual(small.legend[0], { n: 1, policy: 'policy-number-1', traffic: 'faithful' });
  // the placement itself: every box inside, none over another
  const items = Array.from({ length: 30 }, (_, i) => ({ x: 200 + (i % 3), y: 100, r: 4, w: 40, h: 12 }));
  const boxes = placeLabels(items, { bounds: { x: 0, y: 0, w: 400, h: 200 } });
  assert.deepEqual(overlapping(boxes.filter(Boolean)), []);
  assert.ok(boxes.filter(Boolean).length >= 20);
  assert.deepEqual(niceTicks(0, 10, 5).ticks, [0, 2, 4, 6, 8, 10]);
  assert.deepEqual(niceTicks(43.1, 44.9, 4).ticks.map((v) => +v.toFixed(2)), [43.5, 44, 44.5]);
});

test('the bar charts\' labels: names while they fit under their slots, else numbers (every k-th when even those would touch)', () => {
  const labels = ['reference\nfaithful', 'walkthrough\nfaithful', 'seed000\ncalm'];
  const wide = slotLabels(labels, [100, 200, 300], { measure, top: 210 });
  assert.equal(wide.mode, 'names');
  assert.deepEqual(wide.boxes.map((b) => b.lines), [['reference', 'faithful'], ['walkthrough', 'faithful'], ['seed000', 'calm']]);
  assert.equal(wide.boxes[0].h, 26);
  const many = Array.from({ length: 18 }, (_, i) => `policy-number-${i}\nfaithful`);
  const centers = many.map((_, i) => 60 + i * 35);
  const narrow = slotLabels(many, centers, { measure, top: 210 });
  assert.equal(narrow.mode, 'numbers');
  assert.deepEqual(narrow.boxes.map((b) => b.text), many.map((_, i) => String(i + 1)));
  assert.deepEqual(overlapping(narrow.boxes, 1), []);
  const crowded = slotLabels(Array.from({ length: 120 }, (_, i) => `p${i}`), Array.from({ length: 120 }, (_, i) => i * 5), { measure });
  assert.equal(crowded.mode, 'numbers');
  assert.ok(crowded.every > 1 && crowded.boxes.length < 120);
  assert.deepEqual(overlapping(crowded.boxes, 1), []);
  assert.deepEqual(slotLabels([], [], { measure }), { mode: 'names', boxes: [] });
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

test('the page\'s own summary of older runs counts collisions at fault (per second) and near misses when every run has them', () => {
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
  assert.equal(summaryColumns(rows).find((c) => c.group === 'collisions per 100 mi' && c.label === 'at fault (95% CI)').cell(b).text, '–');
  assert.equal(summaryColumns(rows).find((c) => c.group === 'collisions per 100 mi' && c.label === 'all (95% CI)').cell(b).text, '15.00');
  assert.match(collisionsNote(rows), /^Collisions \(every row\): counted for every second of contact/, 'runs from before contacts');
  // runs with nothing at all do not break it either
  assert.equal(summarize([{}]).length, 1);
});

test('the page\'s own summary counts collisions as contacts when every run does, the rubric\'s incidents beside them', () => {
  const contacts = (list) => ({
    total: list.length, at_fault: list.filter((c) => c.at_fault).length, rubric_incidents: list.reduce((a, c) => a + c.rubric_incidents, 0),
    by_kind: { ego_hit_car_ahead: list.filter((c) => c.kind === 'ego_hit_car_ahead').length, hit_from_behind: list.filter((c) => c.kind === 'hit_from_behind').length },
    contacts: list,
  });
  const c1 = { car: 3, t_s: 10, end_t_s: 12.5, s_m: 100, lane: 1, kind: 'ego_hit_car_ahead', at_fault: true, rubric_incidents: 3 };
  const c2 = { car: 7, t_s: 40, end_t_s: 40.2, s_m: 900, lane: 0, kind: 'hit_from_behind', at_fault: false, rubric_incidents: 1 };
  const a1 = run('A', 1, { collisions: contacts([c1, c2]), safety: SAFETY(0.9, 1) });
  a1.incident_counts.collision = 4; // the rubric's: one per second of contact
  const a2 = run('A', 2, { collisions: contacts([]), safety: SAFETY(1.2, 0) });
  a2.incident_counts.collision = 0;
  const [a] = summarize([a1, a2], ['A'], ['faithful']);
  assert.deepEqual(a.collisions, {
    total: 2, per_100mi: 10, per_100mi_ci: null, at_fault: 1, at_fault_per_100mi: 5, at_fault_per_100mi_ci: null,
    by_kind: { ego_hit_car_ahead: 1, hit_from_behind: 1 }, rubric_incidents: 4, rubric_per_100mi: 20,
  });
  const t = cellsOf(a);
  assert.equal(t['collisions (contacts) per 100 mi|all (95% CI)'].text, '10.00');
  assert.match(t['collisions (contacts) per 100 mi|all (95% CI)'].title, /^2 contacts .*the rubric counted 4 collision incidents/);
  assert.equal(collisionsNote([a]), null);
  // runs of both kinds: the per-second count, no at fault (the two do not add up)
  const [mixed] = summarize([a1, run('A', 3, { collisions: { total: 1, at_fault: 1, by_kind: {} } })], ['A'], ['faithful']);
  assert.equal(mixed.collisions.total, 5);
  assert.equal(mixed.collisions.at_fault, null);
  assert.ok(!('rubric_incidents' in mixed.collisions));
  // the chart leaves no row of them out
  assert.equal(scatterLayout([a], { width: 500, height: 300, measure }).points.length, 1);
});
