// Adding jobs (file, drop, pattern), upload progress and errors, placement, the queue.

import { $, el, setAttr, setDisabled, setHidden, setText, syncList } from "../dom.js";
import { bytes, duration, length, percent } from "../format.js";
import { ACTIVE_JOB_STATES, previewJob } from "../store.js";
import { renderLayerPens } from "./pens.js";

// The server resumes stopped and interrupted jobs from their resume line.
const RESUMABLE = new Set(["paused", "interrupted", "stopped"]);
const DELETABLE = new Set(["queued", "done", "failed", "cancelled", "stopped", "interrupted"]);
const STARTABLE = new Set(["queued", "done", "cancelled"]);
// A job started while another runs (or the machine is not ready) waits for its turn.
const CANCELLABLE = new Set(["running", "paused", "pen_change", "interrupted", "waiting"]);
// Started again from the first line, without a new upload.
const RESTARTABLE = new Set(["stopped", "interrupted", "failed"]);

/** Which buttons a job row offers, in the order shown. Pure. */
export function jobButtons(job, waitingIndex, waitingCount, anyActive) {
  const b = [];
  if (STARTABLE.has(job.state)) b.push({ verb: "start", label: anyActive ? "Start next" : "Start" });
  if (job.state === "running") b.push({ verb: "pause", label: "Pause" });
  if (job.state === "pen_change") b.push({ verb: "resume", label: "Continue", aria: "Pen loaded: continue" });
  if (RESUMABLE.has(job.state)) b.push({ verb: "resume", label: "Resume", disabled: anyActive && job.state !== "paused" });
  if (RESTARTABLE.has(job.state)) b.push({ verb: "restart", label: "Restart from the beginning", disabled: anyActive });
  if (CANCELLABLE.has(job.state)) b.push({ verb: "cancel", label: "Cancel" });
  if (job.bounds && !ACTIVE_JOB_STATES.has(job.state)) b.push({ verb: "frame", label: "Frame", aria: "Trace the frame (pen up)", disabled: anyActive });
  if (waitingIndex >= 0) {
    b.push({ verb: "up", label: "↑", aria: "Move up", disabled: waitingIndex === 0 });
    b.push({ verb: "down", label: "↓", aria: "Move down", disabled: waitingIndex === waitingCount - 1 });
  }
  if (DELETABLE.has(job.state)) b.push({ verb: "delete", label: "Delete" });
  return b;
}

const COLOUR = /^#[0-9a-f]{3,8}$/i;

/** A job's layers as the view shows them (none for a single layer: the job's own bar says
 * it all): name, colour, progress and what it takes; `current` is the one being drawn
 * (or whose pen is due). Pure. */
export function layerRows(job) {
  const layers = job.layers || [];
  if (layers.length < 2) return [];
  const active = ACTIVE_JOB_STATES.has(job.state);
  const due = job.state === "pen_change" && job.pen_change ? job.pen_change.layer - 1 : -1;
  const drawing = active && due < 0 ? layers.findIndex((l) => (l.progress || 0) < 1) : -1;
  return layers.map((l, i) => ({
    key: `${i}:${l.first_line}`,
    name: l.name || `layer ${i + 1}`,
    colour: COLOUR.test(l.colour || "") ? l.colour : "",
    progress: l.progress || 0,
    info: `${percent(l.progress || 0)} · est. ${duration(l.estimate_s)} · ${length(l.pen_down_mm)}`,
    current: i === due || i === drawing,
  }));
}

export function bindJobs(actions) {
  const input = $("#file-input");
  input.addEventListener("change", () => {
    for (const file of input.files) actions.uploadFile(file);
    input.value = "";
  });
  const zone = $("#dropzone");
  for (const type of ["dragenter", "dragover"]) {
    document.addEventListener(type, (e) => {
      if (e.dataTransfer && [...e.dataTransfer.types].includes("Files")) {
        e.preventDefault();
        zone.classList.add("over");
      }
    });
  }
  for (const type of ["dragleave", "drop"]) {
    document.addEventListener(type, () => zone.classList.remove("over"));
  }
  document.addEventListener("drop", (e) => {
    if (!e.dataTransfer || !e.dataTransfer.files.length) return;
    e.preventDefault();
    for (const file of e.dataTransfer.files) actions.uploadFile(file);
  });
  $("#pattern-add").addEventListener("click", () => {
    const name = $("#pattern-select").value;
    if (name) actions.addPattern(name);
  });
  const form = $("#placement");
  form.addEventListener("submit", (e) => e.preventDefault());
  // Only the field edited changes: the others keep what the job has.
  const changed = (e) => {
    const patch = placementField(e.target);
    if (patch) actions.placementChanged(patch);
  };
  form.addEventListener("change", changed);
  form.addEventListener("input", (e) => {
    if (e.target.type === "number") changed(e);
  });
  $("#place-here").addEventListener("click", () => actions.placeHere());
  $("#queue").addEventListener("click", (e) => {
    const button = e.target.closest("button[data-verb]");
    const row = e.target.closest("li[data-key]");
    if (button) actions.jobVerb(row.dataset.key, button.dataset.verb);
    else if (row) actions.selectJob(row.dataset.key);
  });
  for (const list of [$("#uploads"), $("#upload-errors")]) {
    list.addEventListener("click", (e) => {
      const button = e.target.closest("button[data-dismiss]");
      if (button) actions.dismissUpload(button.dataset.dismiss);
    });
  }
  $("#upload-clear").addEventListener("click", () => actions.clearFailedUploads());
}

/** One edited placement field as a patch of the form's state; null while a number is
 * half typed. */
function placementField(input) {
  const name = input.name;
  if (input.type === "checkbox") return { [name]: input.checked };
  if (name === "paper") return { paper: input.value };
  if (name === "rotate") return { rotate: parseInt(input.value, 10) || 0 };
  const value = parseFloat(input.value);
  return Number.isFinite(value) ? { [name]: value } : null;
}

function renderPlacement(state) {
  const form = $("#placement");
  const f = form.elements;
  const p = state.placement;
  const put = (input, value, prop = "value") => {
    if (document.activeElement !== input && input[prop] !== value) input[prop] = value;
  };
  put(f.paper, p.paper);
  put(f.landscape, p.landscape, "checked");
  put(f.margin, String(p.margin));
  put(f.fit, p.fit, "checked");
  put(f.rotate, String(p.rotate));
  put(f.scale, String(p.scale));
  put(f.dx, String(p.dx));
  put(f.dy, String(p.dy));
  setDisabled(f.landscape, !p.paper);
  setDisabled(f.margin, !p.paper);
  const job = previewJob(state);
  const m = state.machine;
  setDisabled($("#place-here"), state.serverLost || !(job && job.bounds && m && m.connected && m.position));
  setText($("#place-target"), job && job.state === "queued"
    ? `Applies to new uploads and to the queued job “${job.name}”.`
    : "Applies to new uploads.");
}

function renderUploads(state) {
  const failed = state.uploads.filter((u) => u.status === "failed");
  setHidden($("#upload-failed"), failed.length === 0);
  setText($("#upload-failed-title"), `${failed.length} upload${failed.length === 1 ? "" : "s"} refused`);
  renderUploadList($("#upload-errors"), failed);
  renderUploadList($("#uploads"), state.uploads.filter((u) => u.status !== "failed"));
}

function renderUploadList(list, uploads) {
  syncList(list, uploads, (u) => u.id,
    () => el("li", { className: "upload" },
      el("div", { className: "upload-head" }, el("span", { className: "name" }), el("span", { className: "status" }),
        el("button", { type: "button", className: "link small", "aria-label": "Dismiss" }, "✕")),
      el("progress", { max: 1, value: 0 }),
      el("ul", { className: "errors" })),
    (node, u) => {
      setText(node.querySelector(".name"), u.name);
      const status = u.status === "uploading"
        ? `${bytes(u.loaded)} of ${bytes(u.total)}`
        : u.status === "processing" ? "importing…" : u.message;
      setText(node.querySelector(".status"), status);
      node.classList.toggle("failed", u.status === "failed");
      node.querySelector("button").dataset.dismiss = u.id;
      const bar = node.querySelector("progress");
      setHidden(bar, u.status !== "uploading" && u.status !== "processing");
      if (u.status === "uploading" && u.total) bar.value = u.loaded / u.total;
      else if (u.status === "processing") bar.removeAttribute("value");
      syncList(node.querySelector(".errors"), u.errors || [], (e) => e.key,
        () => el("li", {}, el("span", { className: "line" }), el("span", { className: "msg" })),
        (li, e) => {
          setText(li.querySelector(".line"), e.line ? `line ${e.line}` : "");
          setText(li.querySelector(".msg"), e.message);
        });
    });
}

function renderQueue(state) {
  const waiting = state.jobs.filter((j) => j.state === "queued");
  const anyActive = state.jobs.some((j) => ACTIVE_JOB_STATES.has(j.state));
  const shown = previewJob(state);
  setHidden($("#queue-empty"), state.jobs.length > 0);
  syncList($("#queue"), state.jobs, (j) => j.id,
    () => el("li", { className: "job", tabIndex: -1 },
      el("div", { className: "job-head" },
        el("button", { type: "button", className: "link name", "data-verb": "select" }),
        el("span", { className: "badge" })),
      el("div", { className: "job-meta" }),
      el("div", { className: "job-progress" }, el("progress", { max: 1 }), el("span", { className: "pct" })),
      el("ol", { className: "job-layers", "aria-label": "Layers" }),
      el("p", { className: "error job-error" }),
      el("div", { className: "row wrap layer-pens" }),
      el("div", { className: "row wrap actions" })),
    (node, job) => {
      node.classList.toggle("selected", shown === job);
      const name = node.querySelector(".name");
      setText(name, job.name);
      name.setAttribute("aria-pressed", String(shown === job));
      const badge = node.querySelector(".badge");
      setText(badge, job.state);
      badge.dataset.state = job.state;
      const lines = job.lines_total ? `${job.lines_total} lines` : "";
      const from = job.resume_line && RESUMABLE.has(job.state) && job.state !== "paused" ? `resumes at line ${job.resume_line}` : "";
      const where = job.plotter || job.target;
      const on = where ? `on ${where}` : "";
      const wait = job.state === "waiting" && job.waiting ? `waiting: ${job.waiting}` : "";
      setText(node.querySelector(".job-meta"), [job.format, lines, `est. ${duration(job.estimate_s)}`, from, on, wait].filter(Boolean).join(" · "));
      const showProgress = ["running", "paused", "interrupted", "stopped"].includes(job.state);
      const prog = node.querySelector(".job-progress");
      setHidden(prog, !showProgress);
      if (showProgress) {
        prog.querySelector("progress").value = job.progress || 0;
        const eta = job.state === "running" && !state.serverLost ? ` · ${duration(job.eta_s)} left` : "";
        setText(prog.querySelector(".pct"), `${percent(job.progress)} (${job.lines_done ?? 0}/${job.lines_total ?? "?"})${eta}`);
      }
      renderLayers(node.querySelector(".job-layers"), job);
      const err = node.querySelector(".job-error");
      setText(err, job.error ? (typeof job.error === "string" ? job.error : JSON.stringify(job.error)) : "");
      setHidden(err, !job.error);
      renderLayerPens(node.querySelector(".layer-pens"), job, state.pens.list);
      const idx = waiting.indexOf(job);
      const buttons = jobButtons(job, idx, waiting.length, anyActive);
      const row = node.querySelector(".actions");
      syncList(row, buttons, (b) => b.verb,
        (b) => el("button", { type: "button", "data-verb": b.verb, "aria-label": b.aria }, b.label),
        (btn, b) => setDisabled(btn, Boolean(b.disabled)));
    });
}

function renderLayers(list, job) {
  const rows = layerRows(job);
  setHidden(list, rows.length === 0);
  syncList(list, rows, (r) => r.key,
    () => el("li", { className: "layer" },
      el("span", { className: "swatch", "aria-hidden": "true" }),
      el("span", { className: "layer-name" }),
      el("progress", { max: 1 }),
      el("span", { className: "layer-info" })),
    (li, r) => {
      li.querySelector(".swatch").style.backgroundColor = r.colour;
      setText(li.querySelector(".layer-name"), r.name);
      const bar = li.querySelector("progress");
      bar.value = r.progress;
      setAttr(bar, "aria-label", `${r.name}: ${percent(r.progress)}`);
      setText(li.querySelector(".layer-info"), r.info);
      setAttr(li, "aria-current", r.current ? "step" : null);
    });
}

function renderPatterns(state) {
  const select = $("#pattern-select");
  syncList(select, state.patterns, (p) => p.name,
    (p) => el("option", { value: p.name }),
    (opt, p) => {
      setText(opt, p.name);
      opt.title = p.description || "";
    });
  setDisabled($("#pattern-add"), state.patterns.length === 0);
}

export function renderJobs(state) {
  renderPatterns(state);
  renderUploads(state);
  renderPlacement(state);
  renderQueue(state);
  const job = previewJob(state);
  setText($("#preview-title"), job ? job.name : "Preview");
  const info = [];
  if (job && job.bounds) {
    const b = job.bounds;
    info.push(`drawing ${(b.max_x - b.min_x).toFixed(1)} × ${(b.max_y - b.min_y).toFixed(1)} mm at X ${b.min_x.toFixed(1)}, Y ${b.min_y.toFixed(1)}`);
  }
  const warnings = (job && job.warnings) || []; // e.g. the paper turned to fit
  info.push(...warnings.slice(0, 3).map((w) => w.message));
  if (warnings.length > 3) info.push(`and ${warnings.length - 3} more warnings`);
  const preview = job && state.previews[job.id];
  if (preview && preview.error) info.push(`preview unavailable: ${preview.error}`);
  else if (preview && preview.geom) info.push(`${preview.geom.strokes.count.toLocaleString()} points`);
  setText($("#place-error"), state.placementError || "");
  setText($("#preview-info"), info.join(" · "));
}
