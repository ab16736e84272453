// The bench summary rows, computed from the runs as the bench's summary does, for a report
// object that carries runs but no "summary": the figures without their intervals (those, and
// how precise they are, come only from the bench), collisions as contacts when every run
// counts them so (else the older per-second count), at fault when every run classifies them,
// near misses when every run has them (else null, as the bench writes for older runs).
export const INCIDENT_TYPES = ['collision', 'speeding', 'max_acceleration', 'max_jerk', 'outside_lane'];
const METRES_PER_MILE = 1609.344;
const MPH_PER_MPS = 2.2369362920544025;

function median(values) {
  if (!values.length) return 0;
  const v = [...values].sort((a, b) => a - b);
  const n = v.length;
  return n % 2 ? v[(n - 1) / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

const num = (x) => (typeof x === 'number' && Number.isFinite(x) ? x : 0);
const isNum = (x) => typeof x === 'number' && Number.isFinite(x);
const per100 = (n, miles) => (miles > 0 ? (100 * n) / miles : 0);

// Collisions of runs. When every run counts them as contacts (its collisions list
// `contacts`): contacts in all, at fault and by kind, and the rubric's latched collision
// incidents (one per second of contact) beside them, as the bench writes. Else as an older
// bench wrote them: the rubric's count from the incident counts (a collision for every second
// of contact), at fault and by kind only when every run classified its collisions and none
// counts contacts (the two counts do not add up); no `rubric_incidents` key, which says so.
function collisionsOf(runs, miles) {
  const rubric = runs.reduce((a, r) => a + num((r.incident_counts || {}).collision), 0);
  const contacts = runs.filter((r) => r.collisions && Array.isArray(r.collisions.contacts)).length;
  if (runs.length && contacts === runs.length) {
    const total = runs.reduce((a, r) => a + num(r.collisions.total), 0);
    const atFault = runs.reduce((a, r) => a + num(r.collisions.at_fault), 0);
    return {
      total, per_100mi: per100(total, miles), per_100mi_ci: null,
      at_fault: atFault, at_fault_per_100mi: per100(atFault, miles), at_fault_per_100mi_ci: null,
      by_kind: byKind(runs), rubric_incidents: rubric, rubric_per_100mi: per100(rubric, miles),
    };
  }
  const out = { total: rubric, per_100mi: per100(rubric, miles), per_100mi_ci: null, at_fault: null, at_fault_per_100mi: null, at_fault_per_100mi_ci: null, by_kind: null };
  const classified = runs.every((r) => r.collisions && isNum(r.collisions.at_fault));
  if (!classified || contacts > 0) return out;
  out.at_fault = runs.reduce((a, r) => a + r.collisions.at_fault, 0);
  out.at_fault_per_100mi = per100(out.at_fault, miles);
  out.by_kind = byKind(runs);
  return out;
}

function byKind(runs) {
  const out = {};
  for (const r of runs) {
    for (const [k, n] of Object.entries(r.collisions.by_kind || {})) out[k] = (out[k] || 0) + num(n);
  }
  return out;
}

// Near misses of runs (null unless every run measured them): episodes per 100 miles, the
// least TTC and headway (null when never measured), and the shares of time below the
// thresholds, over all the runs' time.
function nearMissesOf(runs, miles, seconds) {
  if (!runs.every((r) => r.safety && typeof r.safety === 'object')) return null;
  const least = (key) => {
    const v = runs.map((r) => r.safety[key]).filter(isNum);
    return v.length ? Math.min(...v) : null;
  };
  const episodes = runs.reduce((a, r) => a + num(r.safety.near_miss_episodes), 0);
  const s0 = runs[0].safety;
  return {
    episodes,
    per_100mi: per100(episodes, miles),
    per_100mi_ci: null,
    min_ttc_ahead_s: least('min_ttc_ahead_s'),
    min_ttc_entering_s: least('min_ttc_entering_s'),
    min_time_headway_s: least('min_time_headway_s'),
    share_ttc_below: seconds > 0 ? runs.reduce((a, r) => a + num(r.safety.time_ttc_below_s), 0) / seconds : 0,
    share_headway_below: seconds > 0 ? runs.reduce((a, r) => a + num(r.safety.time_headway_below_s), 0) / seconds : 0,
    ttc_threshold_s: isNum(s0.ttc_threshold_s) ? s0.ttc_threshold_s : 1.5,
    headway_threshold_s: isNum(s0.headway_threshold_s) ? s0.headway_threshold_s : 1.0,
  };
}

/// The run's policy and traffic profile.
export function groupOf(run) {
  const c = run.config || {};
  return { policy: c.policy ?? run.policy ?? '?', traffic: c.traffic ?? run.traffic ?? '?' };
}

/// One row per policy and traffic profile, in the order of `policies` × `traffic` (then any
/// other group found in the runs).
export function summarize(runs, policies = [], traffic = []) {
  const order = [];
  const seen = new Set();
  const add = (p, t) => {
    const key = `${p}\u0000${t}`;
    if (!seen.has(key)) {
      seen.add(key);
      order.push([p, t]);
    }
  };
  for (const p of policies) for (const t of traffic) add(p, t);
  for (const r of runs) {
    const g = groupOf(r);
    add(g.policy, g.traffic);
  }
  const rows = [];
  for (const [p, t] of order) {
    const mine = runs.filter((r) => {
      const g = groupOf(r);
      return g.policy === p && g.traffic === t;
    });
    if (!mine.length) continue;
    let miles = 0;
    let seconds = 0;
    const peak = { acc: 0, jerk: 0, sacc: 0, sjerk: 0, p99: 0 };
    const free = [];
    const p50s = [];
    const counts = Object.fromEntries(INCIDENT_TYPES.map((k) => [k, 0]));
    for (const r of mine) {
      miles += num(r.distance_miles);
      seconds += num(r.duration_s);
      free.push(num(r.best_incident_free_miles));
      for (const k of INCIDENT_TYPES) counts[k] += num((r.incident_counts || {})[k]);
      const pk = r.peak || {};
      peak.acc = Math.max(peak.acc, num(pk.acceleration_mps2));
      peak.jerk = Math.max(peak.jerk, num(pk.jerk_mps3));
      peak.sacc = Math.max(peak.sacc, num(pk.strict_acceleration_mps2));
      peak.sjerk = Math.max(peak.sjerk, num(pk.strict_jerk_mps3));
      p50s.push(num((r.timing || {}).p50_us));
      peak.p99 = Math.max(peak.p99, num((r.timing || {}).p99_us));
    }
    const total = INCIDENT_TYPES.reduce((a, k) => a + counts[k], 0);
    rows.push({
      policy: p,
      traffic: t,
      runs: mine.length,
      total_miles: miles,
      mean_speed_mph: seconds > 0 ? ((miles * METRES_PER_MILE) / seconds) * MPH_PER_MPS : 0,
      incidents: total,
      incidents_per_100mi: miles > 0 ? (100 * total) / miles : 0,
      incidents_per_100mi_by_type: Object.fromEntries(INCIDENT_TYPES.map((k) => [k, per100(counts[k], miles)])),
      incident_free_miles_median: median(free),
      incident_free_miles_worst: Math.min(...free),
      peak_acceleration_mps2: peak.acc,
      peak_jerk_mps3: peak.jerk,
      peak_strict_acceleration_mps2: peak.sacc,
      peak_strict_jerk_mps3: peak.sjerk,
      timing: { planner_p50_us_median: median(p50s), planner_p99_us_worst: peak.p99 },
      collisions: collisionsOf(mine, miles),
      near_misses: nearMissesOf(mine, miles, seconds),
      precision: null,
    });
  }
  return rows;
}
