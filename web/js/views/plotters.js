// The plotter switcher: one card per plotter (state, job, progress, Hold, STOP) and
// STOP ALL. Shown only when the server drives more than one plotter.

import { $, el, setHidden, setText, syncList } from "../dom.js";
import { MOVING_STATES } from "../store.js";

export function bindPlotters(actions) {
  $("#plotters").addEventListener("click", (event) => {
    const button = event.target.closest("button");
    if (!button) return;
    const card = button.closest("[data-plotter]");
    if (button.dataset.verb === "stop-all") actions.estopAll();
    else if (card && button.dataset.verb === "stop") actions.estopPlotter(card.dataset.plotter);
    else if (card && button.dataset.verb === "hold") actions.holdPlotter(card.dataset.plotter);
    else if (card) actions.selectPlotter(card.dataset.plotter);
  });
}

export function renderPlotters(state) {
  const names = state.plotterOrder;
  setHidden($("#plotters"), names.length < 2);
  if (names.length < 2) return;
  syncList($("#plotter-cards"), names, (name) => name,
    () => el("li", { className: "plotter-card" },
      el("button", { type: "button", className: "link name", "data-verb": "select" }),
      el("span", { className: "badge" }),
      el("div", { className: "plotter-job" }),
      el("progress", { max: 1 }),
      el("div", { className: "row" },
        el("button", { type: "button", "data-verb": "hold" }, "Hold"),
        el("button", { type: "button", className: "estop-small", "data-verb": "stop" }, "STOP"))),
    (node, name) => {
      const machine = state.plotters[name] || {};
      const job = state.jobs.find((j) => j.plotter === name && ["running", "paused"].includes(j.state));
      node.dataset.plotter = name;
      node.classList.toggle("selected", name === state.plotter);
      const title = node.querySelector(".name");
      setText(title, name);
      title.setAttribute("aria-pressed", String(name === state.plotter));
      const badge = node.querySelector(".badge");
      setText(badge, machine.state || "?");
      badge.dataset.state = machine.state || "";
      setText(node.querySelector(".plotter-job"), job ? `${job.name} (${job.state})` : "no job");
      const bar = node.querySelector("progress");
      setHidden(bar, !job);
      if (job) bar.value = job.progress || 0;
      node.querySelector('[data-verb="hold"]').disabled = !job || !MOVING_STATES.has(machine.state);
    });
}
