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

/** The layer choice sent with a start or a restart: {layers, start_layer}, or {} for all. */
export function layerOptions(job, choice) {
  const count = (job.layers || []).length;
  if (!choice || count < 2) return {};
  const body = {};
  const ticked = choice.ticked.filter((n) => n >= 1 && n <= count);
  if (ticked.length !== count) body.layers = ticked;
  if (choice.start > 1) body.start_layer = choice.start;
  return body;
}

/** The REST request of `action` on `job`: {method, path, body}; `opts`: the layer choice
 * (`layers`), the picked point (`pick`, `overlap`), the queue `position`. Stop is not a
 * request: it is the plotter's emergency stop (estop.js). Pure. */
export function actionRequest(job, action, opts = {}) {
  const path = `/api/jobs/${encodeURIComponent(job.id)}`;
  const post = (verb, body) => ({ method: "POST", path: `${path}/${verb}`, body });
  switch (action) {
    case "delete": return { method: "DELETE", path };
    case "start":
    case "restart": return post(action, layerOptions(job, opts.layers));
    case "resume_from": {
      const p = opts.pick;
      return post(action, { from: { x: p.x, y: p.y }, overlap: opts.overlap || 0 });
    }
    case "move": return post("move", { position: opts.position });
    default: return post(action);
  }
}
