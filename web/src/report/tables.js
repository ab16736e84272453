// The report's tables as data: for each table its columns, each a header and a cell function
// of a row giving {text, cls, title, data}. No DOM here (main.js draws them; the tests read
// them): the summary, the precision, every pair, and the pairs' matrices (a figure's verdicts
// of each policy against each other, the mirror cell of a pair filled from it). Every key may
// be missing (a bench from before intervals, collision classes, contacts, tests or near
// misses, or rows the page summarized itself): a missing figure is '–', a missing interval
// leaves the figure alone.
import { INCIDENT_TYPES } from './summary.js';

export const TYPE_LABELS = { collision: 'collision', speeding: 'speeding', max_acceleration: 'max acc', max_jerk: 'max jerk', outside_lane: 'outside lane' };
const DEFAULT_TTC_S = 1.5;
const DEFAULT_HEADWAY_S = 1.0;
const MINUS = '−';

const isNum = (x) => typeof x === 'number' && Number.isFinite(x);

/// x with d decimals, or '–'.
export const fix = (x, d) => (isNum(x) ? x.toFixed(d) : '–');

/// A 95% interval [lo, hi] with numbers at both ends, or null.
export const ciOf = (ci) => (Array.isArray(ci) && ci.length === 2 && isNum(ci[0]) && isNum(ci[1]) ? ci : null);

/// "43.57 (43.1–44.0)": the figure with d decimals, its interval with dci; the figure alone
/// when there is no interval, '–' when there is no figure.
export function withCI(v, ci, d, dci = d) {
  if (!isNum(v)) return '–';
  const c = ciOf(ci);
  return c ? `${v.toFixed(d)} (${c[0].toFixed(dci)}–${c[1].toFixed(dci)})` : v.toFixed(d);
}

/// A signed figure: "+1.20", "−0.35" (a true minus sign), "0.00".
export function signed(v, d) {
  if (!isNum(v)) return '–';
  const t = Math.abs(v).toFixed(d);
  if (Number(t) === 0) return (0).toFixed(d);
  return `${v > 0 ? '+' : MINUS}${t}`;
}

/// A difference with its interval: "+1.46 (+0.90 to +2.01)" (the ends may have either sign,
/// so "to" and not a dash between them).
export function deltaCI(v, ci, d) {
  if (!isNum(v)) return '–';
  const c = ciOf(ci);
  return c ? `${signed(v, d)} (${signed(c[0], d)} to ${signed(c[1], d)})` : signed(v, d);
}

/// A rate per 100 miles with its interval: "1.23 (0.40–2.90)"; a rate with no event, whose
/// interval is [0, its one-sided 95% upper bound], "0.00 (≤ 0.68)". `oneSided` false for a
/// row of an older bench, whose interval of no event was two-sided (shown as it is).
export function rateWithCI(v, ci, d, oneSided = true) {
  if (!isNum(v)) return '–';
  const c = ciOf(ci);
  if (c && oneSided && v === 0 && c[0] === 0) return `${(0).toFixed(d)} (≤ ${c[1].toFixed(d)})`;
  return withCI(v, ci, d);
}

/// A share (0-1) as a percentage.
export const percent = (x, d = 1) => (isNum(x) ? `${(100 * x).toFixed(d)}%` : '–');

const obj = (x) => (x && typeof x === 'object' && !Array.isArray(x) ? x : {});
const cell = (text, cls = '', title = undefined, data = undefined) => ({ text, cls, title, data });
const num = (text, extra = '', title = undefined) => cell(text, `num${extra ? ` ${extra}` : ''}`, title);

/// True when the row's bench says how it reached its intervals (the `intervals` key, null or
/// why there are none): its rates with no event have one-sided intervals. An older row's are
/// two-sided.
export const oneSidedRates = (r) => 'intervals' in obj(r);

/// True when the row's collisions are contacts (one per car touched); false for collisions
/// of an older bench, counted for every second of contact.
export const countsContacts = (r) => 'rubric_incidents' in obj(obj(r).collisions);

const intervalTitle = (v, ci, d, oneSided) => {
  const c = ciOf(ci);
  if (!c) return undefined;
  if (oneSided && v === 0 && c[0] === 0) return `no event: one-sided 95% upper bound ${c[1].toFixed(d)}`;
  return `95% interval ${c[0].toFixed(d)}–${c[1].toFixed(d)}`;
};

/// The near-miss thresholds the rows were measured with (seconds): the first row's, else the
/// defaults. `headway` is the time gap's (the keys keep the name headway).
export function thresholdsOf(rows) {
  for (const r of rows || []) {
    const n = obj(obj(r).near_misses);
    if (isNum(n.ttc_threshold_s) || isNum(n.headway_threshold_s)) {
      return { ttc: isNum(n.ttc_threshold_s) ? n.ttc_threshold_s : DEFAULT_TTC_S, headway: isNum(n.headway_threshold_s) ? n.headway_threshold_s : DEFAULT_HEADWAY_S };
    }
  }
  return { ttc: DEFAULT_TTC_S, headway: DEFAULT_HEADWAY_S };
}

// "ego hit car ahead 2, car cut in 1" from a by-kind count, or '' when there is none.
function kindsText(byKind) {
  return Object.entries(obj(byKind)).filter(([, n]) => isNum(n) && n > 0)
    .map(([k, n]) => `${k.replace(/_/g, ' ')} ${n}`).join(', ');
}

const BEFORE_CONTACTS = 'counted for every second of contact (a bench from before collisions were counted as contacts)';
const NO_COLLISIONS = 'no collision figures: runs from before collisions were counted as contacts (bench again to compare collisions)';

// Collisions (contacts) per 100 miles, all of them.
function collisionsCell(r) {
  const c = obj(r.collisions);
  if (r.collisions === null && oneSidedRates(r)) return num('–', '', NO_COLLISIONS);
  const notes = [];
  if (countsContacts(r)) {
    if (isNum(c.total)) notes.push(`${c.total} contacts (one per car touched, however long)`);
    notes.push(`the rubric counted ${fix(c.rubric_incidents, 0)} collision incidents (one per second of contact), ${fix(c.rubric_per_100mi, 2)} per 100 mi`);
  } else if (r.collisions) {
    if (isNum(c.total)) notes.push(`${c.total} collisions`);
    notes.push(BEFORE_CONTACTS);
  }
  return num(rateWithCI(c.per_100mi, c.per_100mi_ci, 2, oneSidedRates(r)), c.per_100mi > 0 ? 'bad' : '', notes.join('; ') || undefined);
}

function atFaultCell(r) {
  const c = obj(r.collisions);
  if (r.collisions === null && oneSidedRates(r)) return num('–', '', NO_COLLISIONS);
  const v = c.at_fault_per_100mi;
  const notes = [];
  if (isNum(c.at_fault) && isNum(c.total)) notes.push(`${c.at_fault} of ${c.total} ${countsContacts(r) ? 'contacts' : 'collisions'} at fault`);
  const kinds = kindsText(c.by_kind);
  if (kinds) notes.push(`by kind: ${kinds}`);
  if (r.collisions && !countsContacts(r)) notes.push(BEFORE_CONTACTS);
  return num(rateWithCI(v, c.at_fault_per_100mi_ci, 2, oneSidedRates(r)), v > 0 ? 'bad' : '', notes.join('; ') || undefined);
}

/// What to say with a row, on a line of its own under it: why it has no intervals (too few
/// seeds), the bench's warnings (e.g. one seed holds most of a rate's events). [] when
/// nothing.
export function rowNotes(r) {
  const row = obj(r);
  const out = [];
  if (typeof row.intervals === 'string' && row.intervals) out.push(`no intervals: ${row.intervals}`);
  for (const w of Array.isArray(row.warnings) ? row.warnings : []) if (typeof w === 'string' && w) out.push(`⚠ ${w}`);
  return out;
}

/// What to say once of the rows' collisions: which rows have none (runs from before contacts)
/// and which count them for every second of contact (a bench from before contacts); null when
/// every row counts contacts.
export function collisionsNote(rows) {
  const name = (r) => `${obj(r).policy ?? '?'} / ${obj(r).traffic ?? '?'}`;
  const which = (some) => (some.length === rows.length ? 'every row' : some.map(name).join(', '));
  const none = (rows || []).filter((r) => obj(r).collisions === null && oneSidedRates(r));
  const old = (rows || []).filter((r) => obj(r).collisions && typeof r.collisions === 'object' && !countsContacts(r));
  const out = [];
  if (none.length) out.push(`No collision figures (${which(none)}): ${NO_COLLISIONS.slice(NO_COLLISIONS.indexOf(':') + 2)}.`);
  if (old.length) out.push(`Collisions (${which(old)}): ${BEFORE_CONTACTS}.`);
  return out.length ? out.join(' ') : null;
}

/// The summary table's columns for these rows: {group, label, cell(row)}; a column's group
/// heads the columns next to it that share it. (A row's notes, rowNotes, go on a line of their
/// own under it.)
export function summaryColumns(rows) {
  const th = thresholdsOf(rows);
  const contacts = (rows || []).some(countsContacts);
  const near = (r) => obj(r.near_misses);
  const seconds = (r, key, limit) => {
    // null with near misses measured: no car ahead was ever closing in (or ahead at all)
    const v = near(r)[key];
    return num(isNum(v) ? v.toFixed(2) : (r.near_misses && v === null ? 'none' : '–'), isNum(v) && v < limit ? 'bad' : '');
  };
  return [
    { group: '', label: 'policy', cell: (r) => cell(String(r.policy ?? '?')) },
    { group: '', label: 'traffic', cell: (r) => cell(String(r.traffic ?? '?')) },
    { group: '', label: 'runs', cell: (r) => num(fix(r.runs, 0)) },
    { group: '', label: 'miles', cell: (r) => num(fix(r.total_miles, 1)) },
    { group: 'speed', label: 'mean mph (95% CI)', cell: (r) => num(withCI(r.mean_speed_mph, r.mean_speed_mph_ci, 2, 1)) },
    { group: 'incidents per 100 mi', label: 'all (95% CI)',
      cell: (r) => num(rateWithCI(r.incidents_per_100mi, r.incidents_per_100mi_ci, 1, oneSidedRates(r)), r.incidents_per_100mi > 0 ? 'bad' : '') },
    ...INCIDENT_TYPES.map((k) => ({
      group: 'incidents per 100 mi', label: TYPE_LABELS[k],
      cell: (r) => {
        const v = obj(r.incidents_per_100mi_by_type)[k];
        return num(fix(v, 1), v > 0 ? 'bad' : '', intervalTitle(v, obj(r.incidents_per_100mi_by_type_ci)[k], 1, oneSidedRates(r)));
      },
    })),
    { group: contacts ? 'collisions (contacts) per 100 mi' : 'collisions per 100 mi', label: 'all (95% CI)', cell: collisionsCell },
    { group: contacts ? 'collisions (contacts) per 100 mi' : 'collisions per 100 mi', label: 'at fault (95% CI)', cell: atFaultCell },
    { group: 'near misses', label: 'per 100 mi (95% CI)', cell: (r) => num(rateWithCI(near(r).per_100mi, near(r).per_100mi_ci, 1, oneSidedRates(r)), near(r).per_100mi > 0 ? 'bad' : '', isNum(near(r).episodes) ? `${near(r).episodes} episodes` : undefined) },
    { group: 'near misses', label: 'least TTC ahead (s)', cell: (r) => seconds(r, 'min_ttc_ahead_s', th.ttc) },
    { group: 'near misses', label: 'least time gap (s)', cell: (r) => seconds(r, 'min_time_headway_s', th.headway) },
    { group: 'near misses', label: `TTC < ${th.ttc} s`, cell: (r) => num(percent(near(r).share_ttc_below, 2)) },
    { group: 'near misses', label: `time gap < ${th.headway} s`, cell: (r) => num(percent(near(r).share_headway_below, 2)) },
    { group: 'incident-free mi', label: 'median (95% CI) / worst',
      cell: (r) => num(`${withCI(r.incident_free_miles_median, r.incident_free_miles_median_ci, 2)} / ${fix(r.incident_free_miles_worst, 2)}`) },
    { group: 'peak acc / jerk', label: 'rubric', cell: (r) => num(`${fix(r.peak_acceleration_mps2, 1)} / ${fix(r.peak_jerk_mps3, 1)}`) },
    { group: 'peak acc / jerk', label: 'strict', cell: (r) => num(`${fix(r.peak_strict_acceleration_mps2, 1)} / ${fix(r.peak_strict_jerk_mps3, 1)}`) },
    { group: 'planner µs', label: 'p50 / p99', cell: (r) => num(`${fix(obj(r.timing).planner_p50_us_median, 0)} / ${fix(obj(r.timing).planner_p99_us_worst, 0)}`) },
  ];
}

// The figures whose intervals the precision table shows: its key in a row's "precision",
// what it is, its decimals.
const PRECISION = [
  { key: 'mean_speed_mph', label: 'mean speed (mph)', d: 2 },
  { key: 'incidents_per_100mi', label: 'incidents per 100 mi', d: 1 },
  { key: 'at_fault_collisions_per_100mi', label: 'at-fault collisions per 100 mi', d: 2 },
];

/// True when some row says how precise one of its figures is (a bench from before does not,
/// nor do rows with too few seeds for intervals).
export function hasPrecision(rows) {
  return (rows || []).some((r) => Object.values(obj(obj(r).precision)).some((p) => p && typeof p === 'object'));
}

/// The precision table's columns: per figure, its interval's half width and the seeds that
/// would halve it.
export function precisionColumns() {
  return [
    { group: '', label: 'policy', cell: (r) => cell(String(r.policy ?? '?')) },
    { group: '', label: 'traffic', cell: (r) => cell(String(r.traffic ?? '?')) },
    { group: '', label: 'runs', cell: (r) => num(fix(r.runs, 0)) },
    ...PRECISION.flatMap((f) => [
      { group: f.label, label: '± half width', cell: (r) => {
        const p = obj(obj(r.precision)[f.key]);
        return num(isNum(p.half_width) ? `± ${p.half_width.toFixed(f.d)}` : '–');
      } },
      { group: f.label, label: 'seeds to halve', cell: (r) => num(fix(obj(obj(r.precision)[f.key]).seeds_to_halve, 0)) },
    ]),
  ];
}

/// The figures of a paired comparison, in the table's order: the key in a pair's "figures",
/// the column group, what it is, decimals, whether higher is better.
export const PAIR_FIGURES = [
  { key: 'mean_speed_mph', label: 'Δ mean mph', name: 'mean speed (mph)', d: 2, higher: true },
  { key: 'incidents_per_100mi', label: 'Δ incidents /100 mi', name: 'incidents per 100 mi', d: 1 },
  { key: 'at_fault_collisions_per_100mi', label: 'Δ at-fault collisions /100 mi', name: 'at-fault collisions per 100 mi', d: 2 },
  { key: 'collisions_per_100mi', label: 'Δ collisions /100 mi', name: 'collisions per 100 mi', d: 2, optional: true },
  { key: 'near_misses_per_100mi', label: 'Δ near misses /100 mi', name: 'near misses per 100 mi', d: 1, optional: true },
];

/// The verdicts a figure may have, the class of its cells, and its mark: a sign that tells
/// better from worse without colour.
export const VERDICTS = {
  better: { cls: 'better', mark: '✓', text: 'better' },
  worse: { cls: 'worse', mark: '✗', text: 'worse' },
  'no difference': { cls: 'same', mark: '=', text: 'no difference' },
  'too few seeds': { cls: 'few', mark: '?', text: 'too few seeds' },
};
const MIRRORED_VERDICT = { better: 'worse', worse: 'better' };

/// The pairs as an array (none when the data has no "pairs"), each an object.
export function pairsOf(bench) {
  const p = obj(bench).pairs;
  return Array.isArray(p) ? p.filter((x) => x && typeof x === 'object') : [];
}

/// A p-value: "0.013", "8.9e-5"; '–' when there is none.
export function pValue(p) {
  if (!isNum(p)) return '–';
  if (p >= 0.001 || p === 0) return p.toFixed(3);
  return p.toExponential(1).replace('e-', 'e−');
}

// The probability of improvement with its interval: "0.62 (0.45–0.78)", or as it is.
const chance = (f) => withCI(f.probability_of_improvement, f.probability_of_improvement_ci, 2);

/// The paired table's columns: traffic, the pair, seeds, then per figure the difference with
/// its interval, the probability that A is better (with its interval), the p-value after
/// Holm's correction and the verdict. The figures that no pair has (an older bench) are left
/// out, as are the optional ones (all collisions, near misses) when none has them, and the
/// p-values when no pair has one (a bench from before the tests).
export function pairColumns(pairs) {
  const has = (key) => pairs.some((p) => obj(p.figures)[key] && typeof obj(p.figures)[key] === 'object');
  const figures = PAIR_FIGURES.filter((f) => !f.optional || has(f.key));
  const tested = pairs.some((p) => Object.values(obj(p.figures)).some((f) => obj(f).p_value !== undefined));
  return [
    { group: '', label: 'traffic', cell: (p) => cell(String(p.traffic ?? '?')) },
    { group: '', label: 'A vs B', cell: (p) => cell(`${p.policy ?? '?'} vs ${p.versus ?? '?'}`) },
    { group: '', label: 'seeds', cell: (p) => num(fix(p.seeds, 0)) },
    ...figures.flatMap((f) => {
      const fig = (p) => obj(obj(p.figures)[f.key]);
      const verdict = (p) => (fig(p).verdict === 'better' || fig(p).verdict === 'worse' ? fig(p).verdict : '');
      return [
        { group: f.label, label: 'A − B (95% CI)', cell: (p) => {
          const g = fig(p);
          const title = isNum(g.candidate) && isNum(g.base) ? `${p.policy}: ${g.candidate.toFixed(f.d)}, ${p.versus}: ${g.base.toFixed(f.d)}` : undefined;
          return num(deltaCI(g.difference, g.ci, f.d), verdict(p), title);
        } },
        { group: f.label, label: 'P(A better) (95% CI)', cell: (p) => num(chance(fig(p))) },
        ...(tested ? [{ group: f.label, label: 'p (Holm)', cell: (p) => {
          const g = fig(p);
          const title = isNum(g.p_value) ? `p ${pValue(g.p_value)} before the correction` : (typeof g.verdict === 'string' && g.verdict !== 'too few seeds' ? 'not tested: the same on every seed' : undefined);
          return num(pValue(g.p_adjusted), '', title);
        } }] : []),
        { group: f.label, label: 'verdict', cell: (p) => {
          const v = fig(p).verdict;
          return cell(typeof v === 'string' ? v : '–', `verdict ${verdict(p)}`.trim());
        } },
      ];
    }),
  ];
}

/// A figure of `a` against `b` seen from `b`: the candidate and base swapped, the difference
/// and its interval negated, the probability of improvement (ties counted half) and its
/// interval the complement's, better and worse swapped.
export function mirrorFigure(f) {
  if (!f || typeof f !== 'object') return null;
  const neg = (x) => (isNum(x) ? (x === 0 ? 0 : -x) : x);
  const flip = (x) => (isNum(x) ? 1 - x : x);
  const c = ciOf(f.ci);
  const pc = ciOf(f.probability_of_improvement_ci);
  return {
    ...f,
    candidate: f.base,
    base: f.candidate,
    difference: neg(f.difference),
    ci: c ? [neg(c[1]), neg(c[0])] : (f.ci ?? null),
    probability_of_improvement: flip(f.probability_of_improvement),
    probability_of_improvement_ci: pc ? [flip(pc[1]), flip(pc[0])] : (f.probability_of_improvement_ci ?? null),
    verdict: MIRRORED_VERDICT[f.verdict] ?? f.verdict,
  };
}

/// Policy `a` against `b` on `traffic` for the figure `key`: {pair, figure (null when the pair
/// cannot give it), mirrored (the data has b against a: the figure is its mirror)}, or null
/// when no pair compares them.
export function pairFigure(pairs, traffic, a, b, key) {
  for (const p of pairs) {
    if (String(p.traffic) !== String(traffic)) continue;
    if (p.policy === a && p.versus === b) return { pair: p, figure: obj(p.figures)[key] ?? null, mirrored: false };
  }
  for (const p of pairs) {
    if (String(p.traffic) !== String(traffic)) continue;
    if (p.policy === b && p.versus === a) return { pair: p, figure: mirrorFigure(obj(p.figures)[key] ?? null), mirrored: true };
  }
  return null;
}

/// The traffic profiles of the pairs, in their order.
export const pairTraffic = (pairs) => [...new Set(pairs.map((p) => String(p.traffic)))];

/// The policies compared on `traffic`: those of `order` (the bench's) that some pair has, then
/// any other in the pairs' order.
export function matrixPolicies(pairs, traffic, order = []) {
  const seen = [];
  for (const p of pairs) {
    if (String(p.traffic) !== String(traffic)) continue;
    for (const q of [p.policy, p.versus]) if (typeof q === 'string' && !seen.includes(q)) seen.push(q);
  }
  return [...order.filter((q) => seen.includes(q)), ...seen.filter((q) => !order.includes(q))];
}

/// The hover text of a matrix cell: the pair, both figures, the difference with its interval,
/// P(row better) with its interval, the p-values, the verdict.
function matrixTitle(f, a, b, traffic, found) {
  const g = found.figure;
  const seeds = isNum(found.pair.seeds) ? `, ${found.pair.seeds} seeds` : '';
  const lines = [`${a} vs ${b} (${traffic} traffic${seeds})`];
  if (isNum(g.candidate) && isNum(g.base)) lines.push(`${f.name}: ${a} ${g.candidate.toFixed(f.d)}, ${b} ${g.base.toFixed(f.d)}`);
  lines.push(`${a} − ${b}: ${deltaCI(g.difference, g.ci, f.d)}${ciOf(g.ci) ? ' (95% interval)' : ''}`);
  if (isNum(g.probability_of_improvement)) {
    lines.push(`P(${a} better): ${chance(g)}${ciOf(g.probability_of_improvement_ci) ? ' (95% interval)' : ''}`);
  }
  if (isNum(g.p_adjusted)) lines.push(`p ${pValue(g.p_value)}, Holm-adjusted ${pValue(g.p_adjusted)}`);
  else if (g.verdict === 'no difference' && 'p_value' in g) lines.push('not tested: the same on every seed');
  const v = VERDICTS[g.verdict];
  lines.push(`verdict: ${v ? (g.verdict === 'better' || g.verdict === 'worse' ? `${a} ${g.verdict} than ${b}` : v.text) : '–'}`);
  lines.push(`(${f.higher ? 'higher' : 'lower'} is better${found.mirrored ? `; the data has ${b} vs ${a}, mirrored` : ''})`);
  return lines.join('\n');
}

/// One cell of a figure's matrix: row policy `a` against column policy `b`. Its text is the
/// verdict's mark and the difference a − b; its class the verdict's (`m better`, `m worse`,
/// `m same`, `m few`; `m self` on the diagonal, `m none` without data); its title all the pair
/// says; `data` {verdict, difference, mirrored} for the page and the tests.
export function matrixCell(pairs, f, traffic, a, b) {
  if (a === b) return cell('', 'm self', undefined, { verdict: 'self' });
  const found = pairFigure(pairs, traffic, a, b, f.key);
  if (!found) return cell('', 'm none', `${a} vs ${b}: no pair in the data`, { verdict: 'none' });
  if (!found.figure) return cell('–', 'm none', `${a} vs ${b}: ${f.name} is not in both rows (runs from before it was measured)`, { verdict: 'none' });
  const g = found.figure;
  const v = VERDICTS[g.verdict];
  return cell(`${v ? v.mark : '·'} ${signed(g.difference, f.d)}`, `m ${v ? v.cls : 'unknown'}`, matrixTitle(f, a, b, traffic, found), {
    verdict: typeof g.verdict === 'string' ? g.verdict : 'unknown',
    difference: isNum(g.difference) ? String(g.difference) : '',
    mirrored: String(found.mirrored),
  });
}

/// Policy names longer than this make a matrix number its columns (the rows name them).
const MATRIX_NAME_CHARS = 12;

/// A figure's matrix on one traffic profile as columns over its policies (the rows): the row's
/// policy, then a column per policy with the row's verdict against it. With long names the
/// columns are numbered and each row says its number ("3 a-long-name"); a column's `title` is
/// its policy's name.
export function matrixColumns(pairs, f, traffic, policies) {
  const numbered = policies.some((q) => String(q).length > MATRIX_NAME_CHARS);
  return [
    { group: '', label: 'A \\ B', cell: (a) => cell(numbered ? `${policies.indexOf(a) + 1} ${a}` : String(a), 'm-head') },
    ...policies.map((b, j) => ({ group: '', label: numbered ? String(j + 1) : b, title: b, cell: (a) => matrixCell(pairs, f, traffic, a, b) })),
  ];
}

/// How the verdicts were reached, from the report's `verdicts`: e.g. "Holm over 156 tests, 5%
/// family-wise; paired t-test ... for speed, exact sign-flip ... for rates; no verdict below 8
/// seeds". null for a bench from before (its verdicts: an interval that leaves out 0).
export function verdictMethodText(verdicts) {
  const v = obj(verdicts);
  if (!isNum(v.alpha) && !isNum(v.family_tests)) return null;
  const parts = [];
  parts.push(`${v.correction || 'Holm'} over ${fix(v.family_tests, 0)} tests, ${isNum(v.alpha) ? `${+(100 * v.alpha).toFixed(2)}%` : '–'} family-wise`);
  const tests = [];
  if (v.mean_test) tests.push(`${v.mean_test} for speed`);
  if (v.rate_test) tests.push(`${v.rate_test} for rates`);
  if (tests.length) parts.push(tests.join(', '));
  if (isNum(v.min_seeds)) parts.push(`no verdict below ${v.min_seeds} seeds`);
  return parts.join('; ');
}

/// How the intervals were reached, from the report's `verdicts`, or null.
export function intervalMethodText(verdicts) {
  const v = obj(verdicts);
  const parts = [];
  if (v.mean_interval) parts.push(`mean speed: ${v.mean_interval}`);
  if (v.rate_interval) parts.push(`rates: ${v.rate_interval}`);
  if (v.difference_interval) parts.push(`differences: ${v.difference_interval}`);
  return parts.length ? parts.join('; ') : null;
}

/// The group headers of columns: [{label, span}] runs of the same group.
export function groupsOf(columns) {
  const out = [];
  for (const c of columns) {
    const last = out[out.length - 1];
    if (last && last.label === c.group) last.span += 1;
    else out.push({ label: c.group, span: 1 });
  }
  return out;
}
