// History: the finished jobs in a compact sortable list (name, plotter, pens, started,
// finished, time taken beside the estimate, metres drawn, outcome), plot again, delete,
// clear finished. A name opens the job on the Plot tab (its preview in layer colours).

import { $, el, setAttr, setHidden, setText, syncList } from "../dom.js";
import { duration, length } from "../format.js";
import { can } from "../job-actions.js";
import { jobStateText } from "../words.js";
import { inQueue } from "./jobs.js";
import { penName } from "./pens.js";

const when = (t) => (t ? new Date(t * 1000).toLocaleString([], { dateStyle: "short", timeStyle: "short" }) : "–");
const took = (j) => (j.started_at && j.finished_at ? j.finished_at - j.started_at : null);
/** Pen-down mm drawn: the server's count, else the plan's share of its progress. */
export const drawnMm = (j) => (Number.isFinite(j.drawn_mm) ? j.drawn_mm
  : (j.stats && j.stats.pen_down_mm ? j.stats.pen_down_mm * (j.progress || 0) : 0));

const SORT_KEYS = {
  name: (j) => j.name.toLowerCase(), plotter: (j) => j.plotter || "", started: (j) => j.started_at || 0,
  finished: (j) => j.finished_at || j.created_at || 0, took: (j) => took(j) ?? -1, metres: drawnMm,
  outcome: (j) => j.state,
};

/** The finished jobs, sorted by `sort` (a SORT_KEYS name), `desc` or not. Pure. */
export function historyRows(jobs, sort = "finished", desc = true) {
  const key = SORT_KEYS[sort] || SORT_KEYS.finished;
  const rows = jobs.filter((j) => !inQueue(j));
  rows.sort((a, b) => {
    const x = key(a), y = key(b);
    const c = x < y ? -1 : x > y ? 1 : 0;
    return desc ? -c : c;
  });
  return rows;
}

export function bindHistory(actions, getState) {
  $("#tab-history").addEventListener("click", (e) => {
    const sort = e.target.closest("button[data-sort]");
    if (sort) {
      actions.setHistorySort(sort.dataset.sort);
      return;
    }
    const row = e.target.closest("tr[data-key]");
    const button = e.target.closest("button[data-verb]");
    if (!row || !button) return;
    if (button.dataset.verb === "open") {
      actions.selectJob(row.dataset.key);
      location.hash = "#plot";
    } else actions.jobAction(row.dataset.key, button.dataset.verb);
  });
  $("#history-clear").addEventListener("click", () => {
    actions.clearFinished(historyRows(getState().jobs).filter((j) => can(j, "delete")).map((j) => j.id));
  });
}

export function renderHistory(state) {
  const { sort, desc } = state.history;
  const rows = historyRows(state.jobs, sort, desc);
  setHidden($("#history-empty"), rows.length > 0);
  $("#history-clear").disabled = !rows.some((j) => can(j, "delete"));
  for (const b of document.querySelectorAll("#tab-history button[data-sort]")) {
    setAttr(b.closest("th"), "aria-sort", b.dataset.sort === sort ? (desc ? "descending" : "ascending") : null);
  }
  syncList($("#history-body"), rows, (j) => j.id,
    () => el("tr", {},
      el("td", { "data-label": "Name" }, el("button", { type: "button", className: "link name", "data-verb": "open" })),
      el("td", { className: "plotter", "data-label": "Plotter" }),
      el("td", { className: "pens", "data-label": "Pens" }),
      el("td", { className: "started", "data-label": "Started" }),
      el("td", { className: "finished", "data-label": "Finished" }),
      el("td", { className: "took", "data-label": "Took / est." }),
      el("td", { className: "metres", "data-label": "Drawn" }),
      el("td", { className: "outcome", "data-label": "Outcome" }, el("span", { className: "badge" })),
      el("td", { className: "row wrap actions" })),
    (tr, j) => {
      setText(tr.querySelector(".name"), j.name);
      tr.querySelector(".name").setAttribute("aria-label", `Open “${j.name}” on the Plot tab`);
      setText(tr.querySelector(".plotter"), j.plotter || "–");
      const pens = [...new Set((j.layers || []).map((l) => l.pen).filter((p) => p !== null && p !== undefined))];
      setText(tr.querySelector(".pens"), pens.length ? pens.map((p) => penName(state.pens.list, p)).join(", ") : "–");
      setText(tr.querySelector(".started"), when(j.started_at));
      setText(tr.querySelector(".finished"), when(j.finished_at));
      setText(tr.querySelector(".took"), `${took(j) === null ? "–" : duration(took(j))} / ${duration(j.estimate_s)}`);
      setText(tr.querySelector(".metres"), length(drawnMm(j)));
      const badge = tr.querySelector(".badge");
      setText(badge, jobStateText(j.state));
      badge.dataset.state = j.state;
      const buttons = [can(j, "restart") && { verb: "restart", label: "Plot again" }, can(j, "delete") && { verb: "delete", label: "Delete" }].filter(Boolean);
      syncList(tr.querySelector(".actions"), buttons, (b) => b.verb,
        (b) => el("button", { type: "button", className: "small", "data-verb": b.verb }, b.label),
        (btn, b) => btn.setAttribute("aria-label", `${b.label}: ${j.name}`));
    });
}
