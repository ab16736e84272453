// Units and text for the page. SI inside; mph and miles only here, at the display.
export const MPH_PER_MPS = 2.2369362920544025;
export const METRES_PER_MILE = 1609.344;

/// "hh:mm:ss.cc" for a time in seconds.
export function clock(seconds) {
  const s = Math.max(0, seconds);
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const sec = s - h * 3600 - m * 60;
  const pad = (n, w) => String(n).padStart(w, '0');
  return `${pad(h, 2)}:${pad(m, 2)}:${sec.toFixed(2).padStart(5, '0')}`;
}

const INCIDENT_TEXT = {
  collision: 'Collision',
  speeding: 'Speed limit exceeded',
  max_acceleration: 'Max acceleration exceeded',
  max_jerk: 'Max jerk exceeded',
  outside_lane: 'Outside of lane',
};

/// A collision kind's name as words: 'ego_hit_car_ahead' -> 'ego hit car ahead'.
export const kindText = (kind) => String(kind).replace(/_/g, ' ');

/// The banner text of an incident, with its value where it says something, and for a
/// collision its class ({kind, atFault}, from Replay.incidentClass) when the file has one.
export function incidentText(type, value, cls = null) {
  const head = INCIDENT_TEXT[type] || type;
  switch (type) {
    case 'collision': {
      const what = `${head} with car ${Math.round(value)}`;
      return cls ? `${what} — ${kindText(cls.kind)} (${cls.atFault ? 'at fault' : 'not at fault'})` : what;
    }
    case 'speeding': return `${head}: ${value.toFixed(1)} mph`;
    case 'max_acceleration': return `${head}: ${value.toFixed(1)} m/s²`;
    case 'max_jerk': return `${head}: ${value.toFixed(1)} m/s³`;
    case 'outside_lane': return `${head}: d = ${value.toFixed(2)} m`;
    default: return `${head} (${value})`;
  }
}

/// What the run's report says of how the planner planned: '' when every cycle was planned
/// normally (or the report says nothing), else e.g. 'planner: least-bad 1.0%, fallback 12.3%
/// of cycles'. A planner that fell back on a fifth of its cycles must not look clean.
export function planStatusText(report) {
  const cycles = report && report.plan_status && report.plan_status.cycles;
  const total = report ? Number(report.planner_cycles) : 0;
  if (!cycles || !(total > 0)) return '';
  const leastBad = Number(cycles.least_bad) || 0;
  const fallback = Number(cycles.fallback) || 0;
  if (leastBad + fallback === 0) return '';
  const pct = (n) => `${((100 * n) / total).toFixed(1)}%`;
  return `planner: least-bad ${pct(leastBad)}, fallback ${pct(fallback)} of cycles`;
}

/// The TTC and headway thresholds of the run's near misses (seconds): the report's when it has
/// them, else the defaults (docs/evaluation.md).
export function safetyThresholds(report) {
  const s = (report && report.safety) || {};
  const pos = (x, dflt) => (typeof x === 'number' && x > 0 ? x : dflt);
  return { ttc: pos(s.ttc_threshold_s, 1.5), headway: pos(s.headway_threshold_s, 1.0) };
}

/// What the run's report says of its collisions and near misses, e.g. '2 collisions (1 at
/// fault) · 3 near misses'; '' for a report from before they were counted. No collisions
/// are not mentioned (the status line counts incidents already).
export function safetyStatusText(report) {
  if (!report) return '';
  const parts = [];
  const c = report.collisions;
  if (c && Number(c.total) > 0) {
    const n = Number(c.total);
    const fault = typeof c.at_fault === 'number' ? ` (${c.at_fault} at fault)` : '';
    parts.push(`${n} collision${n === 1 ? '' : 's'}${fault}`);
  }
  const s = report.safety;
  if (s && typeof s.near_miss_episodes === 'number') {
    const n = s.near_miss_episodes;
    parts.push(`${n} near miss${n === 1 ? '' : 'es'}`);
  }
  return parts.join(' · ');
}
