// Header summary, the machine panel, the banners and the emergency-stop panel.

import { $, el, setAttr, setDisabled, setHidden, setText, syncList } from "../dom.js";
import { duration, mm, percent } from "../format.js";
import { can, isActive } from "../job-actions.js";
import { estopConfirmed, holdAction, plotterJob } from "../store.js";
import { ALARMS, machineStateText } from "../words.js";
import { penName } from "./pens.js";

function machineLabel(m) {
  if (!m) return "…";
  if (!m.connected) return "Disconnected";
  return m.state || "Unknown";
}

/** "plotter2: " when there are several plotters, else "". */
const whose = (state, name = state.plotter) => (state.plotterOrder.length > 1 && name ? `${name}: ` : "");

/** The pen prompt of a job at a pen change, in words: names the pen, else the layer (its
 * `name` is the layer's label: a colour in words), never a colour code. */
export function penChangeText(job, pens = []) {
  const p = job.pen_change || {};
  if (p.reason === "reink") return p.message || "re-ink the pen, then continue";
  const pen = p.pen || (job.layers && job.layers[p.layer - 1] && job.layers[p.layer - 1].pen !== null
    && job.layers[p.layer - 1].pen !== undefined ? penName(pens, job.layers[p.layer - 1].pen) : null);
  const layer = `layer ${p.layer} of ${p.layers}${p.name ? ` “${p.name}”` : ""}`;
  return `${layer}: ${pen ? `load pen “${pen}”` : "load the pen for this layer"}, then continue`;
}

/** The header's summary. While the server is unreachable it says so instead of the last
 * state, position and ETA it heard (they may be long out of date). Pure. */
export function headerSummary(state) {
  if (state.serverLost) return { state: "connection lost", badge: "Lost", pos: "", pen: "", job: "" };
  const m = state.machine;
  const label = machineLabel(m);
  const job = plotterJob(state, state.plotter); // the selected plotter's, never another's
  const shown = job && isActive(job) ? job : null;
  const eta = shown && can(shown, "hold") && shown.eta_s ? ` · ${duration(shown.eta_s)} left` : "";
  const text = m && m.connected ? machineStateText(label) : machineStateText(label);
  return {
    state: whose(state) + text, badge: label, pos: positionText(m), pen: m ? `pen ${m.pen}` : "",
    job: shown ? `${shown.name} ${percent(shown.progress)}${eta}` : "",
  };
}

function positionText(m) {
  const p = m && m.position;
  return p ? `X ${mm(p.x)}  Y ${mm(p.y)}` : "";
}

/** Banners for the current state, each with the action that clears it. Pure. */
export function bannersFor(state) {
  const out = [];
  if (state.socket.status !== "open") {
    out.push({
      key: "socket", level: state.serverLost ? "error" : "warn",
      text: state.serverLost
        ? "Lost the live connection to the server: it does not answer. Reconnecting automatically."
        : state.socket.status === "connecting"
          ? "Connecting to the server for live updates…"
          : "Lost the live connection to the server. Reconnecting automatically.",
      actions: [{ label: "Reconnect now", action: "reconnect" }],
    });
  }
  const m = state.machine;
  if (m && !m.connected) {
    out.push({
      key: "link", level: "error",
      text: `${whose(state)}the plotter is not connected (serial link lost). Check its USB cable and power; the server reconnects by itself.`,
      actions: [],
    });
  } else if (m && m.state === "Alarm" && !state.estop) {
    const why = ALARMS[m.alarm] ? `: ${ALARMS[m.alarm]}` : "";
    out.push({
      key: "alarm", level: "error",
      text: `${whose(state)}alarm${m.alarm ? ` ${m.alarm}` : ""}${why}. Home the plotter, or unlock it to go on without homing.`,
      actions: [{ label: "Home", action: "home" }, { label: "Unlock", action: "unlock" }],
    });
  } else if (m && m.state === "Hold") {
    out.push({
      key: "hold", level: "warn", text: `${whose(state)}on hold: the pen is up, the position kept.`,
      actions: [{ label: "Continue", action: plotterJob(state, state.plotter) ? "continue" : "continue-machine", id: (plotterJob(state, state.plotter) || {}).id }],
    });
  }
  for (const job of state.jobs) {
    if (job.pen_change && can(job, "continue")) {
      out.push({
        key: `pen-${job.id}`, level: "warn", text: `${whose(state, job.plotter)}“${job.name}”, ${penChangeText(job, state.pens.list)}.`,
        actions: [{ label: "Continue", action: "continue", id: job.id }],
      });
    }
    if (job.state === "interrupted") {
      const where = job.summary ? ` ${job.summary}` : "";
      out.push({
        key: `int-${job.id}`, level: "warn",
        text: `${whose(state, job.plotter)}“${job.name}” was interrupted (link lost or server restarted).${where}`,
        actions: ["resume", "home_then_resume"].filter((a) => can(job, a))
          .map((a) => ({ label: a === "resume" ? "Resume" : "Home, then resume", action: a, id: job.id })),
      });
    }
  }
  return out;
}

export function bindMachine(actions) {
  $("#banners").addEventListener("click", (e) => {
    const button = e.target.closest("button[data-action]");
    if (button) actions.bannerAction(button.dataset.action, button.dataset.id);
  });
  $("#estop-home").addEventListener("click", (e) => {
    if (e.currentTarget.dataset.all) actions.homeAll();
    else actions.homeStopped();
  });
  $("#estop-unlock").addEventListener("click", () => actions.unlockStopped());
  $("#estop-close").addEventListener("click", () => actions.dismissEstop());
  $("#hold").addEventListener("click", () => actions.holdOrContinue());
  document.addEventListener("keydown", (e) => {
    // H (or the Pause key) holds or continues; never while typing in a field
    if ((e.key !== "h" && e.key !== "H" && e.key !== "Pause") || e.ctrlKey || e.metaKey || e.altKey) return;
    if (e.target.closest && e.target.closest("input, textarea, select, [contenteditable]")) return;
    if (e.repeat) return;
    e.preventDefault();
    actions.holdOrContinue();
  });
}

export function renderMachine(state) {
  const m = state.machine;
  const label = machineLabel(m);
  const sum = headerSummary(state);
  const badge = $("#sum-state");
  setText(badge, sum.state);
  setAttr(badge, "data-state", sum.badge);
  setText($("#sum-pos"), sum.pos);
  setText($("#sum-pen"), sum.pen);
  setText($("#sum-job"), sum.job);

  setText($("#m-conn"), !m ? "…" : m.connected ? "connected" : "not connected");
  setText($("#m-state"), machineStateText(label) + (m && m.alarm ? ` (alarm ${m.alarm}: ${ALARMS[m.alarm] || "see the manual"})` : ""));
  setText($("#m-pos"), positionText(m) || "–");
  setText($("#m-pen"), m ? m.pen : "–");
  setText($("#m-fw"), (m && m.firmware) || "–");

  syncList($("#banners"), bannersFor(state), (b) => b.key,
    () => el("div", { className: "banner", role: "status" }, el("span", { className: "text" }), el("span", { className: "row" })),
    (node, b) => {
      node.className = `banner ${b.level}`;
      setText(node.querySelector(".text"), b.text);
      const row = node.querySelector(".row");
      const want = b.actions.map((a) => `${a.action}:${a.id ?? ""}:${a.label}`).join("|");
      if (row.dataset.want !== want) {
        row.dataset.want = want;
        row.replaceChildren(...b.actions.map((a) =>
          el("button", { type: "button", "data-action": a.action, "data-id": a.id }, a.label)));
      }
    });

  renderEstop(state);
  renderHold(state);
}

/** The big Hold/Continue button: stays focusable (aria-disabled) when there is nothing to hold. */
function renderHold(state) {
  const what = holdAction(state);
  const button = $("#hold");
  setText(button, what === "continue" ? "CONTINUE" : "HOLD");
  setAttr(button, "data-action", what || "");
  setAttr(button, "aria-disabled", String(!what));
}

/** What the stop panel calls what it stopped: "plotter2", "all plotters", "the plotter". Pure. */
export function stoppedWhat(state, e) {
  const names = e.names || [];
  if (e.scope === "all" || names.length > 1) return names.length ? `all plotters (${names.join(", ")})` : "all plotters";
  if (names.length === 1 && state.plotterOrder.length > 1) return names[0];
  return "the plotter";
}

function renderEstop(state) {
  const e = state.estop;
  const panel = $("#estop-panel");
  const appearing = Boolean(e) && panel.hidden;
  setHidden(panel, !e);
  // Wherever the page was scrolled to, the stopped state and what to do next show up.
  if (appearing) panel.scrollIntoView({ block: "nearest" });
  $("#estop").classList.toggle("fired", Boolean(e));
  if (!e) return;
  const confirmed = estopConfirmed(state);
  const phase = e.phase === "failed" ? "failed" : confirmed ? "stopped" : "stopping";
  setAttr(panel, "data-phase", phase);
  const what = stoppedWhat(state, e);
  const several = (e.names || []).length > 1;
  const m = e.names && e.names.length === 1 && e.names[0] !== state.plotter ? state.plotters[e.names[0]] : state.machine;
  if (phase === "failed") {
    setText($("#estop-title"), `Stop of ${what} could not be sent`);
    setText($("#estop-text"), "The server did not answer. Use the stop button on the plotter or cut its power.");
  } else if (phase === "stopping") {
    setText($("#estop-title"), `Stopping ${what}…`);
    setText($("#estop-text"), "Emergency stop sent; waiting for the plotter to confirm.");
  } else {
    const named = what.startsWith("the ") || what.startsWith("all ") ? what.charAt(0).toUpperCase() + what.slice(1) : what;
    const title = `${named} stopped`;
    setText($("#estop-title"), e.remote ? `${title} from another ${e.remote}` : title);
    setText($("#estop-text"), several || (m && m.state === "Alarm")
      ? "Motion was cut, so the position may be lost. Home (recommended), or unlock to go on from here. A stopped job can be resumed from its card or the queue."
      : "Everything queued was dropped. You can start a job again, or home the plotter first.");
  }
  setText($("#estop-error"), e.error || "");
  const busy = phase === "stopping";
  const home = $("#estop-home");
  setText(home, several ? "Home all" : e.names && e.names.length === 1 && state.plotterOrder.length > 1 ? `Home ${e.names[0]}` : "Home");
  home.dataset.all = several ? "1" : "";
  setDisabled(home, busy);
  setHidden($("#estop-unlock"), several);
  setDisabled($("#estop-unlock"), busy);
}
