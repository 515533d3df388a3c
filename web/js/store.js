// The one state object of the page, and the render loop that follows it.
// Actions mutate state through update(); renderers read it; a frame renders once.

import { can, isActive, isResumable } from "./job-actions.js";

// Machine states (the board's, not a job's): moving ones, and the ones a hold stops.
export const MOVING_STATES = new Set(["Run", "Jog", "Home"]);
const HOLDABLE_STATES = new Set(["Run", "Jog"]);
export const DEFAULT_PLACEMENT = { paper: "", landscape: false, margin: 10, fit: false, rotate: 0, scale: 1, dx: 0, dy: 0 };

export function initialState() {
  return {
    view: "starting",         // "starting" (the session not yet asked) | "login" | "app"
    tab: "plot",              // "plot" | "history" | "control" | "pens" | "settings" | "console"
    login: { busy: false, error: "" },
    loginNotice: "",          // why the login page shows (a stale link)
    socket: { status: "closed" },   // "open" | "connecting" | "closed"
    serverLost: false,        // the socket is down and REST cannot reach the server either
    pageId: "",               // this page's random id: tells our stops from other browsers'
    machine: null,            // the machine object of the selected plotter
    machineSeq: 0,            // counts machine reports (machine.seq)
    plotters: {},             // plotter name -> its machine object
    plotterSeq: {},           // plotter name -> machine reports heard
    plotterOrder: [],         // plotter names, the server's order (the first is the default)
    plotter: null,            // the selected plotter's name
    server: null,             // GET /api/server
    jobs: [],                 // queue order
    selectedJobId: null,
    previews: {},             // job id -> { version, data } (the /preview body)
    patterns: [],
    uploads: [],              // { id, name, loaded, total, status, message, errors }
    placement: { ...DEFAULT_PLACEMENT }, // the form: the shown job's, or the user's edit
    placementJob: null,       // the job whose placement the form shows
    placementKey: null,       // and that placement (JSON)
    placementDirty: false,    // an edit not yet applied: the form keeps it
    jog: { step: 10, feed: 3000 },
    settings: { list: null, edits: {}, busy: false, message: "", error: "" },
    pens: { list: [], form: null, busy: false, error: "", message: "" },  // views/pens.js
    fleet: null,              // GET /api/fleet's answer, kept by "fleet" messages
    fleetError: "",
    log: [],                  // { seq, direction, line }
    logSeq: 0,
    estop: null,              // { phase: "sending"|"sent"|"failed", at, acked, via, remote, scope, names }
    notice: null,             // { text, error }
    resumePick: null,         // { jobId, x, y, stroke, along, length, layer }: the point picked
    layerChoice: {},          // job id -> { ticked: [1-based layers], start }: what a start plots
    history: { sort: "finished", desc: true },
    webhooks: { data: null, draft: null, busy: false, message: "", error: "" }, // GET /api/webhooks; draft: the edited text
    settingsAll: false,       // Settings: rows that do not apply to a pen plotter shown too
    penPrompt: null,          // { jobId, action, plotter, pen, loaded, layer }: the pen to load before a start
    loadedPens: {},           // plotter name ("" for the only one) -> the pen id the user said is loaded
    resumeOverlap: 1,         // mm back along the stroke from the picked point
  };
}

export function createStore(state, render) {
  let scheduled = false;
  const flush = () => {
    scheduled = false;
    render(state);
  };
  return {
    state,
    /** Mutate state in `fn`, render in the next frame. */
    update(fn) {
      if (fn) fn(state);
      if (!scheduled) {
        scheduled = true;
        requestAnimationFrame(flush);
      }
    },
    /** Render now (the stop button does not wait for a frame). */
    renderNow() {
      render(state);
    },
  };
}

/** The job whose preview is shown: the selected one, else the selected plotter's active
 * one, else the last one that can be resumed, else the first in the queue; never an
 * unrelated finished job. */
export function previewJob(state) {
  const byId = state.jobs.find((j) => String(j.id) === String(state.selectedJobId));
  return byId ?? plotterJob(state, state.plotter)
    ?? state.jobs.findLast(isResumable)
    ?? state.jobs.find((j) => can(j, "move")) ?? null;
}

/** A plotter's job: the active one on it, else its last stopped or interrupted one, else
 * the first waiting for it. `name` null: any plotter's. */
export function plotterJob(state, name) {
  const on = (j) => !name || !j.plotter || j.plotter === name;
  const onlyOn = (j) => !name || j.plotter === name || j.target === name;
  return state.jobs.find((j) => isActive(j) && on(j))
    ?? state.jobs.findLast((j) => isResumable(j) && onlyOn(j))
    ?? state.jobs.find((j) => j.waiting && onlyOn(j)) ?? null;
}

/** A job of the selected plotter runs (or is held, or waits for a pen). */
export function jobActive(state) {
  const job = plotterJob(state, state.plotter);
  return Boolean(job && isActive(job));
}

/** What the big Hold button does for the selected plotter: "hold", "continue" or null.
 * A job on it offers what its actions say; without one, the board's own hold. */
export function holdAction(state) {
  const m = state.machine;
  if (!m || !m.connected) return null;
  const job = plotterJob(state, state.plotter);
  if (job && can(job, "continue")) return "continue";
  if (job && can(job, "hold")) return "hold";
  if (m.state === "Hold") return "continue";
  if (HOLDABLE_STATES.has(m.state)) return "hold";
  return null;
}

/** A plotter's machine report as the stop sees it: {state, seq}. */
function machineOf(state, name) {
  if (!name || name === state.plotter) return state.machine;
  const m = state.plotters[name];
  return m && { ...m, seq: state.plotterSeq[name] || 0 };
}

/** Whether the stop is confirmed: acknowledged, and every plotter it stopped reports a
 * non-moving state (newer than the click, if it was moving). */
export function estopConfirmed(state) {
  const e = state.estop;
  if (!e || !e.acked) return false;
  const names = e.names && e.names.length ? e.names : [null];
  return names.every((name) => {
    const m = machineOf(state, name);
    if (!m || MOVING_STATES.has(m.state)) return false;
    const before = (e.seqAtClick && typeof e.seqAtClick === "object") ? e.seqAtClick[name ?? ""] : e.seqAtClick;
    return !e.wasMoving || (m.seq || 0) > (before || 0);
  });
}

/** The seq of each plotter's last report now (for estopConfirmed), keyed by name ("" for
 * the selected one when there is one plotter). */
export function seqNow(state, names) {
  const out = {};
  for (const name of names.length ? names : [null]) out[name ?? ""] = (machineOf(state, name) || {}).seq || 0;
  return out;
}
