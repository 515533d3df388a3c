// A job's actions as the server lists them (`job.actions`, docs/INTERNALS.md "The job
// lifecycle"): which buttons a job shows, and the request each action is. The page keeps
// no list of states of its own: what a job may do is what its `actions` say. Pure.

import { ACTION_LABELS } from "./words.js";

const actionsOf = (job) => (job && Array.isArray(job.actions) ? job.actions : []);
export const can = (job, action) => actionsOf(job).includes(action);

/** Plotting now (or held, or at a pen change): it can be stopped. */
export const isActive = (job) => can(job, "stop");
/** Ended where a resume picks it up exactly (stopped, interrupted). */
export const isResumable = (job) => can(job, "resume");

// Shown elsewhere than the job's button row: `edit` opens its placement and pens, `move`
// is the ↑/↓ pair, `resume_from` is the preview's point picker.
const NOT_BUTTONS = new Set(["edit", "move"]);
const ASPECT = { continue: "Pen loaded: continue", frame: "Trace the frame (pen up)" };

/** The buttons of a job's row, in the server's order. `position`: its place among the
 * jobs that can be moved (-1: none), `movable`: how many there are. Pure. */
export function jobButtons(job, position = -1, movable = 0) {
  const out = [];
  for (const action of actionsOf(job)) {
    if (NOT_BUTTONS.has(action)) continue;
    const label = ACTION_LABELS[action] || action.replaceAll("_", " ");
    out.push({ verb: action, label, aria: ASPECT[action] ? `${ASPECT[action]}: ${job.name}` : `${label}: ${job.name}` });
  }
  if (can(job, "move") && position >= 0) {
    out.push({ verb: "up", label: "↑", aria: "Move up", disabled: position === 0 });
    out.push({ verb: "down", label: "↓", aria: "Move down", disabled: position === movable - 1 });
  }
  return out;
}

/** The layer choice sent with a start or a restart: {layers, start_layer}, or {} for all.
 * `choice.start` null: from the first (a resumable job's "where it stopped"). */
export function layerOptions(job, choice) {
  const count = (job.layers || []).length;
  if (!choice || count < 2) return {};
  const body = {};
  const ticked = choice.ticked.filter((n) => n >= 1 && n <= count);
  if (ticked.length !== count) body.layers = ticked;
  if (choice.start > 1) body.start_layer = choice.start;
  return body;
}

/** The layer (1-based) a stopped or interrupted job resumes in: where the pen stopped,
 * else the layer of its resume line (a layer's M0 belongs to the layer after: the
 * server's `layer_runs`); 0 without layers. Pure. */
export function stoppedLayer(job) {
  const layers = job.layers || [];
  if (!layers.length) return 0;
  if (job.done_point && job.done_point.layer) return job.done_point.layer;
  const line = job.resume_line || job.lines_done + 1 || 1;
  let found = 1;
  layers.forEach((l, i) => {
    if (l.first_line - 1 <= line) found = i + 1;
  });
  return found;
}

/** A resume with the layer choice: where it stopped (`resume`) when the plot goes on in
 * that layer, else from the first ticked layer at or after the one chosen to start at
 * (`resume_from` {layer}); `layers`: the ticked ones when not all. {action, body}, or
 * {error} when nothing is left to plot. Pure. */
export function resumeChoice(job, choice) {
  const count = (job.layers || []).length;
  if (!choice || count < 2) return { action: "resume", body: {} };
  const ticked = choice.ticked.filter((n) => n >= 1 && n <= count);
  const body = ticked.length !== count ? { layers: ticked } : {};
  const here = stoppedLayer(job);
  const start = choice.start || here;
  const first = ticked.find((n) => n >= start);
  if (!first) return { error: `no layer ticked from layer ${start} on: tick one to plot` };
  if (first === here && start === here) return { action: "resume", body };
  return { action: "resume_from", body: { ...body, from: { layer: first } } };
}

/** The options of `action` on `job` (its REST body, the WebSocket message's words);
 * `opts`: the layer choice (`layers`), a resume's body (`body`: resumeChoice's), the
 * picked point (`pick`, `overlap`, `home`), the queue `position`. Pure. */
export function actionBody(job, action, opts = {}) {
  switch (action) {
    case "start":
    case "restart": return layerOptions(job, opts.layers);
    case "resume":
    case "home_then_resume": return opts.body || {}; // resumeChoice's
    case "resume_from": {
      const p = opts.pick;
      if (!p) return opts.body || {};
      const layers = opts.layers ? layerOptions(job, opts.layers).layers : undefined;
      const body = { from: { x: p.x, y: p.y }, overlap: opts.overlap || 0, ...(layers ? { layers } : {}) };
      return opts.home ? { ...body, home: true } : body;
    }
    case "move": return { position: opts.position };
    default: return {};
  }
}

/** The REST request of `action` on `job`: {method, path, body} (the fallback while the
 * WebSocket is down). Stop is not a request: it is the plotter's emergency stop
 * (estop.js). Pure. */
export function actionRequest(job, action, opts = {}) {
  const path = `/api/jobs/${encodeURIComponent(job.id)}`;
  if (action === "delete") return { method: "DELETE", path };
  return { method: "POST", path: `${path}/${action}`, body: actionBody(job, action, opts) };
}

/** The WebSocket form of the same action: one `job_action` message (jobs/actions.py). Pure. */
export function actionMessage(job, action, opts = {}) {
  return { type: "job_action", job: String(job.id), action, ...actionBody(job, action, opts) };
}
