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
/// collision its contact (from 0, as Replay.incidentContact; -1 for none: "contact 2" is the
/// second car touched) and its class ({kind, atFault}, from Replay.incidentClass) when the
/// file has them.
export function incidentText(type, value, cls = null, contact = -1) {
  const head = INCIDENT_TEXT[type] || type;
  switch (type) {
    case 'collision': {
      const numbered = typeof contact === 'number' && contact >= 0 ? ` (contact ${contact + 1})` : '';
      const what = `${head} with car ${Math.round(value)}${numbered}`;
      return cls ? `${what} — ${kindText(cls.kind)} (${cls.atFault ? 'at fault' : 'not at fault'})` : what;
    }
    case 'speeding': return `${head}: ${value.toFixed(1)} mph`;
    case 'max_acceleration': return `${head}: ${value.toFixed(1)} m/s²`;
    case 'max_jerk': return `${head}: ${value.toFixed(1)} m/s³`;
    case 'outside_lane': return `${head}: d = ${value.toFixed(2)} m`;
    default: return `${head} (${value})`;
  }
}

/// What a latched collision incident adds to its contact's text: the rubric counts a
/// collision incident for every second of contact, the contact is one collision. `nth` is
/// this incident's place among its contact's (from 1), `of` how many it has.
export function latchedText(nth, of) {
  return `still in contact: the rubric's collision incident ${nth} of ${of} (one per second of contact; one collision)`;
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

const plural = (n, one, many) => `${n} ${n === 1 ? one : many}`;

/// What the run's report says of its collisions, counted as contacts (one per car touched,
/// however long), beside the rubric's latched count: e.g. '3 collisions (contacts), 2 at
/// fault; the rubric counted 7 collision incidents (one per second of contact)'. A report from
/// before contacts (collisions without `contacts`) counted a collision for every second of
/// contact: its figures as they are, saying so. '' without collisions.
export function collisionsText(report) {
  const c = report && report.collisions;
  if (!c || typeof c !== 'object' || !(Number(c.total) > 0)) return '';
  const n = Number(c.total);
  const fault = typeof c.at_fault === 'number' ? c.at_fault : null;
  if (!Array.isArray(c.contacts)) {
    return `${plural(n, 'collision', 'collisions')}${fault === null ? '' : ` (${fault} at fault)`}, counted before contacts (one per second of contact)`;
  }
  let text = `${n} collision${n === 1 ? '' : 's'} (contact${n === 1 ? '' : 's'})${fault === null ? '' : `, ${fault} at fault`}`;
  if (typeof c.rubric_incidents === 'number') {
    text += `; the rubric counted ${plural(c.rubric_incidents, 'collision incident', 'collision incidents')} (one per second of contact)`;
  }
  return text;
}

/// What the run's report says of its collisions and near misses, e.g. '2 collisions
/// (contacts), 1 at fault; the rubric counted 5 collision incidents (one per second of contact)
/// · 3 near misses'; '' for a report from before they were counted. No collisions are not
/// mentioned (the status line counts incidents already).
export function safetyStatusText(report) {
  if (!report) return '';
  const parts = [];
  const collisions = collisionsText(report);
  if (collisions) parts.push(collisions);
  const s = report.safety;
  if (s && typeof s.near_miss_episodes === 'number') {
    const n = s.near_miss_episodes;
    parts.push(`${n} near miss${n === 1 ? '' : 'es'}`);
  }
  return parts.join(' · ');
}

/// The replay's name in `cutCommand` when the page does not know the file's name.
export const REPLAY_PLACEHOLDER = 'REPLAY.otr';

/// A word for a POSIX shell: as it is when it has no special characters, else in single
/// quotes (a quote inside as '\'').
export function shellWord(word) {
  const w = String(word);
  if (/^[A-Za-z0-9_./+:=@%,-]+$/.test(w)) return w;
  return `'${w.replace(/'/g, "'\\''")}'`;
}

/// The command that cuts a scenario from the replay `file` around time `t` (seconds, run
/// time), e.g. 'overtake cut run.otr --at 1064.44 -o cut-1064.json'; `traffic` 'replayed'
/// adds --traffic replayed (reactive, the CLI's default, adds nothing).
export function cutCommand(file, t, traffic = 'reactive') {
  const at = Math.max(0, t).toFixed(2);
  const out = `cut-${at.slice(0, at.indexOf('.'))}.json`;
  const extra = traffic === 'replayed' ? ' --traffic replayed' : '';
  return `overtake cut ${shellWord(file || REPLAY_PLACEHOLDER)} --at ${at} -o ${out}${extra}`;
}

/// Where a cut scenario's replay was cut from (Replay.cutFrom), e.g. 'Cut from t2s5.otr at t
/// 1064.44 s — reference, faithful traffic, seed 5: collision hit_from_behind (not at fault)
/// at t 1064.44 s'; what the origin lacks is left out.
export function cutOriginText(c) {
  if (!c) return '';
  const from = c.replay ? ` from ${c.replay}` : '';
  const run = [];
  if (c.policy) run.push(c.policy);
  if (c.traffic) run.push(`${c.traffic} traffic`);
  if (c.seed !== null && c.seed !== undefined && c.seed !== '') run.push(`seed ${c.seed}`);
  const incident = c.incident ? `: ${c.incident}` : '';
  return `Cut${from} at t ${c.atS.toFixed(2)} s${run.length ? ` — ${run.join(', ')}` : ''}${incident}`;
}
