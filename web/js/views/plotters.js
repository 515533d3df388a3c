// The plotter switcher: one card per plotter (its state, its job with the job's actions,
// progress, STOP) and STOP ALL. Shown only when the server drives more than one plotter.

import { $, el, setAttr, setHidden, setText, syncList } from "../dom.js";
import { percent } from "../format.js";
import { jobButtons } from "../job-actions.js";
import { plotterJob } from "../store.js";
import { jobStateText, machineStateText } from "../words.js";

// A card offers its job's actions except these (the queue has them); its own STOP is always there.
const NOT_ON_CARD = new Set(["stop", "up", "down", "frame", "delete", "resume_from"]);

/** A card's buttons: its job's actions (Hold turns into Continue as the job's actions do),
 * else the board's own hold or continue. Pure. */
export function cardButtons(state, name) {
  const job = plotterJob(state, name);
  if (job) return jobButtons(job).filter((b) => !NOT_ON_CARD.has(b.verb)).map((b) => ({ ...b, job: job.id }));
  const m = state.plotters[name] || {};
  if (m.state === "Hold") return [{ verb: "continue", label: "Continue", aria: `Continue: ${name}` }];
  if (m.state === "Run" || m.state === "Jog") return [{ verb: "hold", label: "Hold", aria: `Hold: ${name}` }];
  return [];
}

export function bindPlotters(actions) {
  $("#plotters").addEventListener("click", (event) => {
    const button = event.target.closest("button");
    if (!button) return;
    const card = button.closest("[data-plotter]");
    const verb = button.dataset.verb;
    if (verb === "stop-all") actions.stop({ all: true });
    else if (!card) return;
    else if (verb === "stop") actions.stop({ plotter: card.dataset.plotter });
    else if (button.dataset.job) actions.jobAction(button.dataset.job, verb);
    else if (verb === "hold" || verb === "continue") actions.holdPlotter(card.dataset.plotter, verb);
    else actions.selectPlotter(card.dataset.plotter);
  });
}

export function renderPlotters(state) {
  const names = state.plotterOrder;
  setHidden($("#plotters"), names.length < 2);
  if (names.length < 2) return;
  syncList($("#plotter-cards"), names, (name) => name,
    () => el("li", { className: "plotter-card" },
      el("div", { className: "row" },
        el("button", { type: "button", className: "link name", "data-verb": "select" }),
        el("span", { className: "badge" })),
      el("div", { className: "plotter-job" }),
      el("progress", { max: 1 }),
      el("div", { className: "row wrap" },
        el("span", { className: "card-actions row wrap" }),
        el("button", { type: "button", className: "estop-small", "data-verb": "stop" }, "STOP"))),
    (node, name) => {
      const machine = state.plotters[name] || {};
      const job = plotterJob(state, name);
      node.dataset.plotter = name;
      node.classList.toggle("selected", name === state.plotter);
      const title = node.querySelector(".name");
      setText(title, name);
      title.setAttribute("aria-pressed", String(name === state.plotter));
      const badge = node.querySelector(".badge");
      const connected = machine.connected !== false;
      setText(badge, connected ? machineStateText(machine.state || "?") : "not connected");
      badge.dataset.state = connected ? machine.state || "" : "Disconnected";
      // the state first: on a phone the line ends in an ellipsis
      setText(node.querySelector(".plotter-job"), job
        ? `${jobStateText(job.state)}${job.progress ? `, ${percent(job.progress)}` : ""}: ${job.name}` : "no job");
      setAttr(node.querySelector(".plotter-job"), "title", job ? job.name : null);
      const bar = node.querySelector("progress");
      setHidden(bar, !job || !job.progress);
      if (job) bar.value = job.progress || 0;
      node.querySelector('[data-verb="stop"]').setAttribute("aria-label", `STOP ${name}`);
      syncList(node.querySelector(".card-actions"), cardButtons(state, name), (b) => `${b.verb}:${b.job ?? ""}`,
        (b) => el("button", { type: "button", className: "small", "data-verb": b.verb, "data-job": b.job }, b.label),
        (btn, b) => setAttr(btn, "aria-label", `${b.label}: ${name}`));
    });
}
