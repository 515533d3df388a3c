// Manual control: jog pad, step size, feed, home, pen, motors, unlock.

import { $, setDisabled, setText } from "../dom.js";
import { MOVING_STATES, jobActive } from "../store.js";

/** Why manual control is unavailable, or "" when it is. Pure. */
export function controlLock(state) {
  const m = state.machine;
  if (jobActive(state)) return "Disabled while a job is running or paused.";
  if (!m || !m.connected) return "The plotter is not connected.";
  if (MOVING_STATES.has(m.state) && m.state !== "Jog") return `Busy (${m.state}).`;
  if (m.state === "Alarm") return "In alarm: only Home and Unlock work until it is cleared.";
  return "";
}

export function bindControl(actions) {
  for (const radio of document.querySelectorAll("input[name=step]")) {
    radio.addEventListener("change", () => actions.setJog({ step: parseFloat(radio.value) }));
  }
  $("#jog-feed").addEventListener("change", (e) => {
    const feed = parseFloat(e.target.value);
    if (feed > 0) actions.setJog({ feed });
  });
  for (const button of document.querySelectorAll(".jog")) {
    button.addEventListener("click", () => actions.jog(parseFloat(button.dataset.dx), parseFloat(button.dataset.dy)));
  }
  $("#ctl-home").addEventListener("click", () => actions.home());
  $("#ctl-home-pad").addEventListener("click", () => actions.home());
  $("#ctl-unlock").addEventListener("click", () => actions.unlock());
  $("#ctl-pen-up").addEventListener("click", () => actions.pen(false));
  $("#ctl-pen-down").addEventListener("click", () => actions.pen(true));
  $("#ctl-motors-off").addEventListener("click", () => actions.motors(false));
}

export function renderControl(state) {
  const lock = controlLock(state);
  setText($("#control-lock"), lock);
  const alarm = state.machine && state.machine.state === "Alarm";
  const running = jobActive(state);
  const disconnected = !state.machine || !state.machine.connected;
  for (const b of document.querySelectorAll(".jog, #ctl-pen-up, #ctl-pen-down, #ctl-motors-off")) {
    setDisabled(b, Boolean(lock));
  }
  for (const b of document.querySelectorAll("#ctl-home, #ctl-home-pad, #ctl-unlock")) {
    setDisabled(b, running || disconnected || (Boolean(lock) && !alarm));
  }
  for (const radio of document.querySelectorAll("input[name=step]")) {
    const want = parseFloat(radio.value) === state.jog.step;
    if (radio.checked !== want) radio.checked = want;
  }
  const feed = $("#jog-feed");
  if (document.activeElement !== feed && feed.value !== String(state.jog.feed)) feed.value = String(state.jog.feed);
  setText($("#control-error"), state.controlError || "");
}
