// The fleet tab: every plotter of every bridge on the MQTT broker (the store's `fleet`,
// which "fleet" messages keep fresh), a STOP per plotter (through the broker for another
// bridge's), STOP EVERYTHING, a link to each bridge's own page, and where this bridge's
// fleet jobs run. Builds its panel inside #tab-fleet; renders from the state.

import { $, el, setHidden, setText, syncList } from "../dom.js";

const POLL_MS = 2000; // only while the socket is down

let pending = false; // a read of /api/fleet is on its way

export function bindFleet(actions) {
  const panel = $("#tab-fleet");
  panel.append(
    el("div", { className: "card fleet-head" },
      el("h2", { id: "fleet-title" }, "Fleet"),
      el("p", { id: "fleet-status", className: "muted" }),
      el("button", { type: "button", id: "fleet-stop-all", className: "estop-all", "data-verb": "stop-everything" },
        "STOP EVERYTHING")),
    el("ul", { id: "fleet-bridges", className: "fleet-bridges" }),
    el("section", { className: "card", "aria-labelledby": "fleet-jobs-title" },
      el("h2", { id: "fleet-jobs-title" }, "Fleet jobs uploaded here"),
      el("ul", { id: "fleet-jobs", className: "fleet-jobs" })));
  // STOP acts on pointerdown (no waiting for the click to complete); keyboard clicks too
  let pointerAt = -Infinity;
  const act = (event) => {
    const button = event.target.closest("button[data-verb]");
    if (!button) return;
    if (event.type === "pointerdown") pointerAt = performance.now();
    else if (performance.now() - pointerAt < 1000) return;
    if (button.dataset.verb === "stop-everything") actions.fleetStop("/api/fleet/estop", {});
    else if (button.dataset.verb === "fleet-stop") {
      actions.fleetStop("/api/fleet/stop", { bridge: button.dataset.bridge, plotter: button.dataset.plotter });
    }
  };
  panel.addEventListener("pointerdown", act);
  panel.addEventListener("click", act);
}

/** Called by the page's render while the fleet tab is shown: the view comes from the
 * socket; REST reads it at once when there is none yet, and every POLL_MS without a socket. */
export function renderFleet(state, actions) {
  if ((!state.fleet || state.socket.status !== "open") && !pending) {
    pending = true;
    setTimeout(async () => {
      await actions.refreshFleet();
      pending = false;
    }, state.fleet ? POLL_MS : 0);
  }
  draw(state.fleet, state.fleetError);
}

function draw(fleet, error) {
  const f = fleet || { enabled: false, bridges: [], jobs: [] };
  setText($("#fleet-title"), f.enabled ? `Fleet ${f.fleet}` : "Fleet");
  setText($("#fleet-status"), error || (!fleet ? "loading..." : !f.enabled
    ? "MQTT is off: start the server with --mqtt mqtt://HOST:PORT to see the fleet."
    : `This bridge: ${f.bridge}, broker ${f.connected ? "connected" : "not connected"}.`));
  setHidden($("#fleet-stop-all"), !fleet);
  syncList($("#fleet-bridges"), f.bridges, (b) => b.bridge,
    () => el("li", { className: "card fleet-bridge" },
      el("h3", {}, el("a", { className: "bridge-link" }), " ", el("span", { className: "badge" })),
      el("ul", { className: "plotter-cards" })),
    (node, b) => {
      const link = node.querySelector(".bridge-link");
      setText(link, b.bridge);
      if (link.getAttribute("href") !== b.url) link.setAttribute("href", b.url || "#");
      const badge = node.querySelector(".badge");
      setText(badge, b.online ? "online" : "offline");
      badge.dataset.state = b.online ? "Idle" : "Disconnected";
      syncList(node.querySelector(".plotter-cards"), b.plotters, (p) => p.name,
        () => el("li", { className: "plotter-card fleet-plotter" },
          el("strong", { className: "name" }), " ", el("span", { className: "badge" }),
          el("div", { className: "plotter-job" }), el("progress", { max: 100 }),
          el("div", { className: "pen-prompt" }),
          el("button", { type: "button", className: "estop-small", "data-verb": "fleet-stop" }, "STOP")),
        (card, p) => {
          setText(card.querySelector(".name"), p.name);
          const state = card.querySelector(".badge");
          setText(state, p.state);
          state.dataset.state = p.state;
          setText(card.querySelector(".plotter-job"), p.job ? `${p.job} (${p.job_state})` : "no job");
          const bar = card.querySelector("progress");
          setHidden(bar, !p.job);
          bar.value = p.progress || 0;
          setText(card.querySelector(".pen-prompt"), p.pen_prompt || "");
          const button = card.querySelector("button");
          button.dataset.bridge = b.bridge;
          button.dataset.plotter = p.name;
          button.setAttribute("aria-label", `STOP ${p.name} of ${b.bridge}`);
        });
    });
  syncList($("#fleet-jobs"), f.jobs || [], (j) => j.id,
    () => el("li", { className: "fleet-job" }, el("span", { className: "what" }), el("progress", { max: 1 })),
    (node, j) => {
      const where = j.bridge ? ` on ${j.bridge}/${j.plotter}` : "";
      setText(node.querySelector(".what"), `${j.name}: ${j.state}${where}${j.job_state && j.bridge ? `, ${j.job_state}` : ""}`);
      node.querySelector("progress").value = j.progress || 0;
    });
}
