// Resume from a point: a click on the preview picks the nearest point on any stroke of a
// job whose actions include resume_from; the panel names its layer and how far along
// its stroke it lies, offers the overlap, and "Resume from here" plots from there (with
// "Home, then resume" where the job's actions offer it).

import { $, setDisabled, setHidden, setText } from "../dom.js";
import { layerTitle } from "../format.js";
import { can } from "../job-actions.js";
import { previewJob } from "../store.js";

export function bindResume(actions) {
  $("#resume-overlap").addEventListener("change", (e) => actions.setResumeOverlap(e.target.value));
  const job = () => $("#resume-point").dataset.job;
  $("#resume-here").addEventListener("click", () => actions.resumeFromPoint(job(), false));
  $("#home-resume").addEventListener("click", () => actions.resumeFromPoint(job(), true));
}

/** The picked point in words: its layer, where along its stroke, where on the paper. Pure. */
export function pickText(job, pick) {
  const layer = pick.layer && job.layers && job.layers[pick.layer - 1];
  const named = layer ? `layer ${pick.layer} “${layerTitle(layer, pick.layer)}”, ` : "";
  const along = Number.isFinite(pick.along) ? `${pick.along.toFixed(1)} mm along a ${(pick.length || 0).toFixed(1)} mm stroke, ` : "";
  return `From ${named}${along}at X ${pick.x.toFixed(2)} Y ${pick.y.toFixed(2)}`;
}

export function renderResume(state) {
  const job = previewJob(state);
  const panel = $("#resume-point");
  const shown = Boolean(job) && can(job, "resume_from");
  setHidden(panel, !shown);
  if (!shown) return;
  panel.dataset.job = job.id;
  const pick = state.resumePick && state.resumePick.jobId === job.id ? state.resumePick : null;
  setText($("#resume-point-text"), pick ? pickText(job, pick) : "Click a line of the drawing to pick where the pen starts again.");
  const overlap = $("#resume-overlap");
  if (document.activeElement !== overlap) overlap.value = String(state.resumeOverlap);
  setDisabled($("#resume-here"), !pick);
  setHidden($("#home-resume"), !can(job, "home_then_resume"));
  setText($("#home-resume"), pick ? "Home, then resume from here" : "Home, then resume");
}
