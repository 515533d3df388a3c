// Resume from a point: a click on the preview picks the nearest stroke vertex of a
// stopped, interrupted or finished job; "Resume from here" plots from there with an
// overlap back along the stroke; after an emergency stop, "Home, then resume".

import { $, setDisabled, setHidden, setText } from "../dom.js";
import { previewJob } from "../store.js";

/** The job states a point can be picked in (the server's resume-from-point states). */
export const PICKABLE = new Set(["stopped", "interrupted", "done", "failed", "cancelled"]);

export function bindResume(actions) {
  $("#resume-overlap").addEventListener("change", (e) => actions.setResumeOverlap(e.target.value));
  const job = () => $("#resume-point").dataset.job;
  $("#resume-here").addEventListener("click", () => actions.resumeFromPoint(job(), false));
  $("#home-resume").addEventListener("click", () => actions.resumeFromPoint(job(), true));
}

export function renderResume(state) {
  const job = previewJob(state);
  const panel = $("#resume-point");
  setHidden(panel, !job || !PICKABLE.has(job.state));
  if (!job || !PICKABLE.has(job.state)) return;
  panel.dataset.job = job.id;
  const pick = state.resumePick && state.resumePick.jobId === job.id ? state.resumePick : null;
  setText($("#resume-point-text"), pick
    ? `from X ${pick.x.toFixed(2)}, Y ${pick.y.toFixed(2)}`
    : "Click the drawing to pick a point to resume from");
  const overlap = $("#resume-overlap");
  if (document.activeElement !== overlap) overlap.value = String(state.resumeOverlap);
  setDisabled($("#resume-here"), !pick);
  setHidden($("#home-resume"), job.state !== "stopped");
  setText($("#home-resume"), pick ? "Home, then resume from here" : "Home, then resume");
}
