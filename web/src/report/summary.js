// The bench summary rows, computed from the runs as src/app/bench.cpp's summarize_bench does,
// for a report object that carries runs but no "summary".
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
      incidents_per_100mi_by_type: Object.fromEntries(INCIDENT_TYPES.map((k) => [k, miles > 0 ? (100 * counts[k]) / miles : 0])),
      incident_free_miles_median: median(free),
      incident_free_miles_worst: Math.min(...free),
      peak_acceleration_mps2: peak.acc,
      peak_jerk_mps3: peak.jerk,
      peak_strict_acceleration_mps2: peak.sacc,
      peak_strict_jerk_mps3: peak.sjerk,
      timing: { planner_p50_us_median: median(p50s), planner_p99_us_worst: peak.p99 },
    });
  }
  return rows;
}
