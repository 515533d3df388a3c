// Entry point: wires the state, the socket, the stop button, the views and the preview.

import { createActions } from "./actions.js";
import { api, setUnauthorizedHandler } from "./api.js";
import { $, setDisabled, setHidden, setText } from "./dom.js";
import { createEstop } from "./estop.js";
import { PreviewCanvas } from "./preview.js";
import { isActive, isResumable } from "./job-actions.js";
import { paperRect, pointsDone, refineWithPen } from "./preview-data.js";
import { createSocket } from "./socket.js";
import { createStore, initialState, previewJob } from "./store.js";
import { bindConsole, renderConsole } from "./views/console.js";
import { bindControl, renderControl } from "./views/control.js";
import { bindFleet, renderFleet } from "./views/fleet.js";
import { bindHistory, renderHistory } from "./views/history.js";
import { bindJobs, renderJobs } from "./views/jobs.js";
import { bindMachine, renderMachine } from "./views/machine.js";
import { bindPens, penName, renderPens } from "./views/pens.js";
import "./views/people.js"; // roles: hides what the role cannot do; approvals; people and keys
import { bindPlotters, renderPlotters } from "./views/plotters.js";
import { bindResume, renderResume } from "./views/resume.js";
import { bindSettings, renderSettings } from "./views/settings.js";

const TABS = ["plot", "history", "control", "pens", "settings", "console", "fleet"];

let preview = null;
let noticeTimer = null;
let shownNotice = null;

function workArea(state) {
  const list = state.settings.list || [];
  const get = (id) => Number((list.find((s) => String(s.id) === id) || {}).value);
  const w = get("130"), h = get("131");
  return w > 0 && h > 0 ? [w, h] : [300, 220];
}

function renderPreview(state) {
  if (!preview) return;
  preview.setWorkArea(...workArea(state));
  const job = previewJob(state);
  const entry = job && state.previews[job.id];
  const geom = entry && entry.geom ? entry.geom : null;
  preview.setGeometry(geom);
  // the paper the placement centres on, with its margins dashed (an offset moves the
  // drawing on it: the preview shows when that leaves the margins)
  const paper = job ? paperRect(job.placement) : null;
  preview.setPaper(paper && { ...paper, margin: job.placement.margin ?? 10 });
  const m = state.machine;
  const pen = !state.serverLost && m && m.connected && m.position ? { x: m.position.x, y: m.position.y, down: m.pen === "down" } : null;
  preview.setPen(pen);
  const pick = state.resumePick;
  preview.setPicked(job && pick && pick.jobId === job.id ? pick : null);
  // The drawn overlay: what the pen has done (the server's lines_done, which stops at the
  // resume point) while a job runs or can be resumed; a finished job keeps its layer colours.
  let done = 0;
  let tail = null;
  if (geom && job && (isActive(job) || isResumable(job))) {
    done = pointsDone(geom, job.lines_done || 0, job.lines_total || 0);
    if (isActive(job) && pen) {
      const found = refineWithPen(geom, done, pen);
      if (found !== null) {
        done = found;
        tail = pen.down ? pen : null;
      }
    }
  }
  preview.setDone(done, tail);
}

/** Before a start, or a resume from a layer's start: load the pen that layer needs
 * (named, never a colour code). */
function renderPenPrompt(state) {
  const p = state.penPrompt;
  setHidden($("#pen-prompt"), !p);
  if (!p) return;
  const job = state.jobs.find((j) => String(j.id) === String(p.jobId));
  const name = (id) => penName(state.pens.list, id);
  const on = p.plotter ? ` on ${p.plotter}` : "";
  const last = p.loaded === null || p.loaded === undefined
    ? "plotbridge does not know which pen is loaded"
    : `the plotter last drew with “${name(p.loaded)}”`;
  const resuming = p.action === "resume" || p.action === "home_then_resume";
  const goes = resuming ? "goes on from" : "starts with";
  setText($("#pen-prompt-text"), `“${job ? job.name : "the job"}” ${goes} layer ${p.layer} “${p.layerName}”: load pen “${name(p.pen)}”${on} (${last}).`);
  setText($("#pen-prompt button[data-answer=loaded]"), resuming ? "Pen loaded: resume" : "Pen loaded: start");
}

function renderNotice(state) {
  const node = $("#notice");
  const n = state.notice;
  setHidden(node, !n);
  if (!n) return;
  setText(node, n.text);
  node.classList.toggle("error", Boolean(n.error));
  if (shownNotice !== n) {
    shownNotice = n;
    clearTimeout(noticeTimer);
    noticeTimer = setTimeout(() => store.update((st) => {
      if (st.notice === n) st.notice = null;
    }), 6000);
  }
}

function render(state) {
  const inApp = state.view === "app";
  setHidden($("#login-view"), state.view !== "login"); // neither shows while starting
  setHidden($("#app"), !inApp);
  if (!inApp) {
    setText($("#login-error"), state.login.error);
    setText($("#login-notice"), state.loginNotice);
    setDisabled($("#login-submit"), state.login.busy);
    return;
  }
  for (const tab of TABS) setHidden($(`#tab-${tab}`), state.tab !== tab);
  for (const button of document.querySelectorAll(".tab")) {
    const current = button.dataset.tab === state.tab;
    button.classList.toggle("current", current);
    if (current) button.setAttribute("aria-current", "page");
    else button.removeAttribute("aria-current");
  }
  renderMachine(state);
  renderPlotters(state);
  renderNotice(state);
  renderPenPrompt(state);
  if (state.tab === "plot") {
    renderJobs(state);
    renderPreview(state);
    renderResume(state);
  } else if (state.tab === "history") renderHistory(state);
  else if (state.tab === "control") renderControl(state);
  else if (state.tab === "pens") renderPens(state);
  else if (state.tab === "settings") renderSettings(state);
  else if (state.tab === "fleet") renderFleet(state, actions);
  else renderConsole(state);
}

const store = createStore(initialState(), render);
const socket = createSocket({
  onMessage: (msg) => actions.onSocketMessage(msg),
  onStatus: (status) => actions.onSocketStatus(status),
});
const estop = createEstop({ socket, store });
const actions = createActions(store, socket, estop);
setUnauthorizedHandler(() => {
  if (store.state.view === "app") actions.leaveApp();
});

/** Leaving the settings with unsaved edits asks first; true when the page may go on. */
function mayLeaveSettings(next) {
  const st = store.state;
  const n = Object.keys(st.settings.edits).length;
  if (st.tab !== "settings" || next === "settings" || n === 0) return true;
  if (!window.confirm(`Discard ${n} unsaved setting change${n > 1 ? "s" : ""}?`)) return false;
  store.update((s) => {
    s.settings.edits = {};
  });
  return true;
}

function tabFromHash() {
  const hash = location.hash.slice(1);
  const tab = TABS.includes(hash) ? hash : "plot";
  if (!mayLeaveSettings(tab)) {
    history.replaceState(null, "", "#settings");
    return;
  }
  store.update((st) => {
    st.tab = tab;
  });
  if (tab === "settings" && store.state.view === "app") actions.loadWebhooks();
}

function bind() {
  // The stop button acts on pointerdown too: no waiting for the click to complete.
  const stop = $("#estop");
  let pointerAt = -Infinity;
  stop.addEventListener("pointerdown", (e) => {
    if (e.button !== 0) return;
    pointerAt = performance.now();
    estop.trigger();
  });
  stop.addEventListener("click", () => {
    // keyboard (Enter/Space) and assistive tech click without a pointerdown first
    if (performance.now() - pointerAt > 1000) estop.trigger();
  });
  document.addEventListener("keydown", (e) => {
    // Esc in a text field only leaves the field: typing must never stop the machine
    if (e.key === "Escape" && typingIn(e.target)) {
      e.target.blur();
      return;
    }
    if (e.key === "Escape" && store.state.view === "app") {
      e.preventDefault();
      estop.trigger();
    }
  });

  $("#login-form").addEventListener("submit", (e) => {
    e.preventDefault();
    const input = $("#login-token");
    const token = input.value.trim();
    input.value = ""; // not left in the page once sent
    actions.login(token);
  });
  $("#logout").addEventListener("click", () => actions.logout());
  for (const button of document.querySelectorAll(".tab")) {
    button.addEventListener("click", () => {
      if (!mayLeaveSettings(button.dataset.tab)) return;
      history.replaceState(null, "", `#${button.dataset.tab}`);
      tabFromHash();
    });
  }
  window.addEventListener("hashchange", tabFromHash);
  window.addEventListener("beforeunload", (e) => {
    if (Object.keys(store.state.settings.edits).length === 0) return;
    e.preventDefault(); // the browser asks whether to leave with unsaved settings
    e.returnValue = "";
  });

  $("#zoom-in").addEventListener("click", () => preview.zoomCenter(1.5));
  $("#zoom-out").addEventListener("click", () => preview.zoomCenter(1 / 1.5));
  $("#zoom-fit").addEventListener("click", () => preview.fitView());

  bindMachine(actions);
  bindPlotters(actions);
  bindJobs(actions);
  bindControl(actions);
  bindPens(actions.pens);
  bindHistory(actions, () => store.state);
  $("#pen-prompt").addEventListener("click", (e) => {
    const button = e.target.closest("button[data-answer]");
    if (button) actions.penPromptAnswer(button.dataset.answer === "loaded");
  });
  bindSettings(actions);
  bindConsole(actions);
  bindResume(actions);
  bindFleet(actions);
}

async function start() {
  bind();
  preview = new PreviewCanvas($("#preview"));
  preview.onPick = (p) => actions.pickAt(p);
  tabFromHash();
  // for debugging in the browser console, and for the browser tests' measurements
  window.plotbridge = { store, actions, preview };
  // A stale login link (/login?token=OLD) lands here with ?link=stale: the login page says why.
  const stale = new URLSearchParams(location.search).get("link") === "stale";
  if (stale) history.replaceState(null, "", location.pathname + location.hash);
  try {
    const session = await api.get("/api/session");
    if (session.logged_in) {
      actions.enterApp();
      return;
    }
  } catch {
    actions.enterApp(); // the server does not answer: the banners say so, and it retries
    return;
  }
  store.update((st) => {
    st.view = "login";
    if (stale) st.loginNotice = "That login link is no longer valid (the server's token changed). Enter the current token, or open the new link that `plotbridge token` prints.";
  });
}

start();

/** A field that takes typed text (where Esc is an editing key, not the stop key). */
function typingIn(target) {
  if (!(target instanceof HTMLElement)) return false;
  if (target.isContentEditable || target.tagName === "TEXTAREA") return true;
  const NOT_TEXT = ["button", "checkbox", "radio", "range", "color", "file", "submit", "reset"];
  return target.tagName === "INPUT" && !NOT_TEXT.includes(target.type);
}
