// Browser notifications while the page is in the background: a pen change is due, or a
// job ended. Permission is asked once, from the click that starts a job (browsers refuse
// a prompt without a user gesture, and a refusal is never asked again).

import { isActive } from "./job-actions.js";
import { penChangeText } from "./views/machine.js";

const ENDED = { done: "is done", failed: "failed", stopped: "was stopped", cancelled: "was cancelled", interrupted: "was interrupted" };

let asked = false;

const supported = () => typeof Notification !== "undefined";

/** What to tell when a job went from `before` (or nothing) to `job`, or null. Pure. */
export function jobNotice(before, job) {
  const was = before ? before.state : null;
  if (was === job.state) return null;
  if (job.state === "pen_change") {
    const body = job.pen_change ? `“${job.name}”, ${penChangeText(job)}` : `“${job.name}” waits for a pen change`;
    return { title: "plotbridge: change the pen", body, tag: `pen-${job.id}` };
  }
  if (ENDED[job.state] && before && isActive(before)) {
    const body = job.error || (job.state === "done" ? "The plot is finished." : "");
    return { title: `plotbridge: “${job.name}” ${ENDED[job.state]}`, body, tag: `job-${job.id}` };
  }
  return null;
}

/** Shows the job's notice when the page is hidden and notifications are allowed. */
export function notifyJob(before, job) {
  if (!document.hidden || !supported() || Notification.permission !== "granted") return;
  const notice = jobNotice(before, job);
  if (notice) new Notification(notice.title, { body: notice.body, tag: notice.tag });
}

/** Asks for permission once per page, only if the user was never asked (call from a click). */
export function askPermission() {
  if (asked || !supported() || Notification.permission !== "default") return;
  asked = true;
  Notification.requestPermission().catch(() => {});
}
