// Header summary, the machine panel, the banners and the emergency-stop panel.

import { $, el, setAttr, setDisabled, setHidden, setText, syncList } from "../dom.js";
import { ALARMS, duration, mm, percent } from "../format.js";
import { ACTIVE_JOB_STATES, estopConfirmed, holdAction } from "../store.js";

function machineLabel(m) {
  if (!m) return "…";
  if (!m.connected) return "Disconnected";
  return m.state || "Unknown";
}

/** The header's summary. While the server is unreachable it says so instead of the last
 * state, position and ETA it heard (they may be long out of date). Pure. */
export function headerSummary(state) {
  if (state.serverLost) return { state: "connection lost", badge: "Lost", pos: "", pen: "", job: "" };
  const m = state.machine;
  const label = machineLabel(m);
  const job = state.jobs.find((j) => ACTIVE_JOB_STATES.has(j.state));
  const eta = job && job.state === "running" && job.eta_s ? ` · ${duration(job.eta_s)} left` : "";
  return {
    state: label, badge: label, pos: positionText(m), pen: m ? `pen ${m.pen}` : "",
    job: job ? `${job.name} ${percent(job.progress)}${eta}` : "",
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
      text: "The plotter is not connected (serial link lost). Check its USB cable and power; the server reconnects by itself.",
      actions: [],
    });
  } else if (m && m.state === "Alarm" && !state.estop) {
    const why = ALARMS[m.alarm] ? `: ${ALARMS[m.alarm]}` : "";
    out.push({
      key: "alarm", level: "error",
      text: `Alarm${m.alarm ? ` ${m.alarm}` : ""}${why}. Home the machine, or unlock it to continue without homing.`,
      actions: [{ label: "Home", action: "home" }, { label: "Unlock", action: "unlock" }],
    });
  } else if (m && m.state === "Hold") {
    out.push({
      key: "hold", level: "warn", text: "Paused (feed hold).",
      actions: [{ label: "Resume", action: "resume" }],
    });
  }
  for (const job of state.jobs) {
    if (job.state === "pen_change" && job.pen_change) {
      out.push({
        key: `pen-${job.id}`, level: "warn", text: `“${job.name}”: ${job.pen_change.message}.`,
        actions: [{ label: "Continue", action: "resume-job", id: job.id }],
      });
    }
    if (job.state === "interrupted") {
      out.push({
        key: `int-${job.id}`, level: "warn",
        text: `“${job.name}” was interrupted${job.resume_line ? ` at line ${job.resume_line}` : ""} (link lost or server restarted).`,
        actions: [{ label: "Resume", action: "resume-job", id: job.id }],
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
  $("#estop-home").addEventListener("click", () => actions.home());
  $("#estop-unlock").addEventListener("click", () => actions.unlock());
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
  setText($("#m-state"), label + (m && m.alarm ? ` (alarm ${m.alarm})` : ""));
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
  const m = state.machine;
  if (phase === "failed") {
    setText($("#estop-title"), "Stop could not be sent");
    setText($("#estop-text"), "The server did not answer. Use the stop button on the machine or cut its power.");
  } else if (phase === "stopping") {
    setText($("#estop-title"), "Stopping…");
    setText($("#estop-text"), "Emergency stop sent; waiting for the machine to confirm.");
  } else {
    setText($("#estop-title"), e.remote ? `Machine stopped from another ${e.remote}` : "Machine stopped");
    setText($("#estop-text"), m && m.state === "Alarm"
      ? "Motion was cut, so the position may be lost. Home the machine (recommended), or unlock it to continue from here. The stopped job can be resumed from the queue."
      : "Everything queued was dropped. You can start a job again, or home the machine first.");
  }
  setText($("#estop-error"), e.error || "");
  const busy = phase === "stopping";
  setDisabled($("#estop-home"), busy);
  setDisabled($("#estop-unlock"), busy);
}
