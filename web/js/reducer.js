// Incoming messages as a pure function of the state: reduce(state, msg) returns the next
// state (a new object; the one passed in is not changed). Side effects (fetching a
// preview, notifications, reading settings) stay in actions.js.

import { isActive } from "./job-actions.js";
import { DEFAULT_PLACEMENT, MOVING_STATES, estopConfirmed, previewJob, seqNow } from "./store.js";

const sameId = (a, b) => String(a) === String(b);
const body = (msg, key) => (msg[key] && typeof msg[key] === "object" ? msg[key] : msg);

/** The form's state from a job's placement. */
export function placementFromJob(placement, fallback) {
  if (!placement) return fallback;
  let paper = placement.paper || "";
  let landscape = false;
  if (paper.endsWith("-landscape")) {
    paper = paper.slice(0, -"-landscape".length);
    landscape = true;
  }
  const pick = (key) => placement[key] ?? fallback[key];
  return {
    paper, landscape, margin: pick("margin"), fit: pick("fit"), rotate: pick("rotate"),
    scale: pick("scale"), dx: pick("dx"), dy: pick("dy"),
  };
}

/** The placement form follows the shown job: when another job is shown, and when the shown
 * job's placement changes while no edit of the user's is pending. */
export function withPlacement(state) {
  const job = previewJob(state);
  if (!job) return state;
  const key = JSON.stringify(job.placement ?? null);
  const sameJob = sameId(state.placementJob, job.id);
  if (sameJob && (key === state.placementKey || state.placementDirty)) return state;
  return {
    ...state, placement: placementFromJob(job.placement, DEFAULT_PLACEMENT),
    placementJob: job.id, placementKey: key, placementDirty: false,
  };
}

/** A machine report of the selected plotter. The stop panel goes when its condition
 * ends, whichever page ended it: the board left the Alarm for Idle (homed or unlocked). */
function withMachine(state, m) {
  const machineSeq = state.machineSeq + 1;
  const next = { ...state, machine: { ...m, seq: machineSeq }, machineSeq };
  const was = state.machine;
  const cleared = was && was.state === "Alarm" && m.connected && m.state === "Idle";
  if (cleared && state.estop && estopConfirmed(next)) next.estop = null;
  return next;
}

function onMachine(state, name, m) {
  let next = state;
  if (name) {
    next = {
      ...state,
      plotterOrder: state.plotterOrder.includes(name) ? state.plotterOrder : [...state.plotterOrder, name],
      plotters: { ...state.plotters, [name]: m },
      plotterSeq: { ...state.plotterSeq, [name]: (state.plotterSeq[name] || 0) + 1 },
      plotter: state.plotter ?? name,
    };
  }
  return !name || name === next.plotter ? withMachine(next, m) : next;
}

function upsertJob(state, job) {
  const i = state.jobs.findIndex((j) => sameId(j.id, job.id));
  const before = i >= 0 ? state.jobs[i] : null;
  const jobs = i >= 0 ? state.jobs.map((j, k) => (k === i ? { ...j, ...job } : j)) : [...state.jobs, job];
  const next = { ...state, jobs };
  // a job started (here or elsewhere) ends the stopped state the panel is about
  if (state.estop && state.estop.acked && isActive(next.jobs[i >= 0 ? i : jobs.length - 1]) && !(before && isActive(before))) {
    next.estop = null;
  }
  return next;
}

/** A plotter was stopped. By this page: its panel is up already. By another page or
 * client: this page shows the stop too, naming the plotter and saying where it came from. */
function onStopped(state, msg) {
  if (state.plotter && msg.plotter && msg.plotter !== state.plotter && !(state.estop && state.estop.remote)) {
    return state; // another plotter's: its card shows it
  }
  if (msg.origin && msg.origin === state.pageId) return state; // ours: the panel is up
  if (state.estop && !state.estop.remote) return state; // this page stopped it too
  const names = msg.plotter ? [msg.plotter] : [];
  if (state.estop && state.estop.remote) {
    const all = [...new Set([...(state.estop.names || []), ...names])];
    return { ...state, estop: { ...state.estop, names: all } };
  }
  const m = state.machine;
  const job = state.jobs.find((j) => isActive(j) && (!msg.plotter || j.plotter === msg.plotter));
  return {
    ...state,
    estop: {
      phase: "sent", acked: true, remote: msg.origin ? "browser" : "client", at: 0, error: "",
      scope: "plotter", names, seqAtClick: seqNow(state, names),
      wasMoving: Boolean(job) || Boolean(m && MOVING_STATES.has(m.state)),
    },
  };
}

export function reduce(state, msg) {
  switch (msg.type) {
    case "machine":
      return onMachine(state, msg.plotter, body(msg, "machine"));
    case "job":
      return withPlacement(upsertJob(state, body(msg, "job")));
    case "jobs":
      return Array.isArray(msg.jobs) ? withPlacement({ ...state, jobs: msg.jobs }) : state;
    case "job_deleted":
      return withPlacement({ ...state, jobs: state.jobs.filter((j) => !sameId(j.id, msg.id)) });
    case "queue": {
      if (!Array.isArray(msg.order)) return state;
      const rank = new Map(msg.order.map((id, i) => [String(id), i]));
      const at = (j) => rank.get(String(j.id)) ?? -1;
      return { ...state, jobs: [...state.jobs].sort((a, b) => at(a) - at(b)) };
    }
    case "stopped":
      return onStopped(state, msg);
    case "pens":
      return Array.isArray(msg.pens) ? { ...state, pens: { ...state.pens, list: msg.pens } } : state;
    case "fleet":
      return msg.fleet && typeof msg.fleet === "object" ? { ...state, fleet: msg.fleet } : state;
    default:
      return state;
  }
}
