// The one state object of the page, and the render loop that follows it.
// Actions mutate state through update(); renderers read it; a frame renders once.

export const MOVING_STATES = new Set(["Run", "Jog", "Home"]);
export const ACTIVE_JOB_STATES = new Set(["running", "paused", "pen_change"]);
// A job in one of these wants the user's eyes: its preview is shown unless one is selected.
const ATTENTION_STATES = new Set(["stopped", "interrupted"]);
export const DEFAULT_PLACEMENT = { paper: "", landscape: false, margin: 10, fit: false, rotate: 0, scale: 1, dx: 0, dy: 0 };
const HOLDABLE_STATES = new Set(["Run", "Jog"]);

export function initialState() {
  return {
    view: "login",            // "login" | "app"
    tab: "plot",              // "plot" | "control" | "pens" | "settings" | "console"
    login: { busy: false, error: "" },
    socket: { status: "closed" },   // "open" | "connecting" | "closed"
    serverLost: false,        // the socket is down and REST cannot reach the server either
    pageId: "",               // this page's random id: tells our stops from other browsers'
    machine: null,            // the machine object of the selected plotter
    machineSeq: 0,            // counts machine reports (machine.seq)
    plotters: {},             // plotter name -> its machine object
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
    log: [],                  // { seq, direction, line }
    logSeq: 0,
    estop: null,              // { phase: "sending"|"sent"|"failed", at, acked, via, remote }
    notice: null,             // { text, error }
    resumePick: null,         // { jobId, x, y }: the stroke vertex picked to resume from
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

/** The job whose preview is shown: the selected one, else the running (or paused) one,
 * else the last stopped or interrupted one, else the first waiting; never an unrelated
 * finished job. */
export function previewJob(state) {
  const byId = state.jobs.find((j) => String(j.id) === String(state.selectedJobId));
  return byId ?? state.jobs.find((j) => ACTIVE_JOB_STATES.has(j.state))
    ?? state.jobs.findLast((j) => ATTENTION_STATES.has(j.state))
    ?? state.jobs.find((j) => j.state === "queued" || j.state === "waiting") ?? null;
}

export function jobActive(state) {
  return state.jobs.some((j) => ACTIVE_JOB_STATES.has(j.state));
}

/** What the big Hold button does for the selected plotter: "hold", "continue" or null. */
export function holdAction(state) {
  const m = state.machine;
  if (!m || !m.connected) return null;
  const mine = (j) => !state.plotter || !j.plotter || j.plotter === state.plotter;
  const job = state.jobs.find((j) => ACTIVE_JOB_STATES.has(j.state) && mine(j));
  if (m.state === "Hold" || (job && job.state !== "running")) return "continue";
  if (HOLDABLE_STATES.has(m.state) || job) return "hold";
  return null;
}

/** Whether the stop is confirmed: acknowledged, and the board reports a non-moving state. */
export function estopConfirmed(state) {
  const e = state.estop;
  if (!e || !e.acked) return false;
  const m = state.machine;
  if (!m || MOVING_STATES.has(m.state)) return false;
  // If it was moving, wait for a machine report newer than the click.
  return !e.wasMoving || m.seq > e.seqAtClick;
}
