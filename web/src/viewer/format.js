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

/// The banner text of an incident, with its value where it says something.
export function incidentText(type, value) {
  const head = INCIDENT_TEXT[type] || type;
  switch (type) {
    case 'collision': return `${head} with car ${Math.round(value)}`;
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
