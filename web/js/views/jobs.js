// Adding jobs (file, drop, pattern), upload progress and errors, placement, the queue.

import { $, el, setAttr, setDisabled, setHidden, setText, syncList } from "../dom.js";
import { layerChoice } from "../actions/jobs.js";
import { bytes, duration, layerTitle, length, mm, percent } from "../format.js";
import { can, isActive, isResumable, jobButtons, stoppedLayer } from "../job-actions.js";
import { previewJob } from "../store.js";
import { errorText, jobStateText } from "../words.js";
import { penName } from "./pens.js";

const COLOUR = /^#[0-9a-f]{3,8}$/i;

/** A job that belongs in the queue (something can be done with it now: start, move,
 * continue, stop, resume) rather than in the history. Pure. */
export const inQueue = (job) => ["start", "move", "stop", "resume"].some((a) => can(job, a));

/** A job's layers as its row shows them: name, colour, pen, progress, what it takes,
 * whether it is ticked to plot and where the plot starts (a stopped job's: where it
 * stopped, `resumesHere`, unless another is chosen); `current` is the one being drawn (or
 * whose pen is due). Pure. */
export function layerRows(job, choice, pens = []) {
  const layers = job.layers || [];
  const due = job.pen_change ? job.pen_change.layer - 1 : -1;
  const drawing = isActive(job) && due < 0 ? layers.findIndex((l) => (l.progress || 0) < 1) : -1;
  const here = isResumable(job) ? stoppedLayer(job) : 0;
  const start = choice ? choice.start || here || 1 : 1;
  return layers.map((l, i) => ({
    key: `${i}:${l.first_line}`,
    number: i + 1,
    name: layerTitle(l, i + 1),
    colour: COLOUR.test(l.colour || "") ? l.colour : "",
    pen: l.pen ?? null,
    penName: l.pen === null || l.pen === undefined ? "" : penName(pens, l.pen),
    progress: l.progress || 0,
    info: `${percent(l.progress || 0)} · est. ${duration(l.estimate_s)} · ${length(l.pen_down_mm)}`,
    current: i === due || i === drawing,
    ticked: !choice || choice.ticked.includes(i + 1),
    start: start === i + 1,
    resumesHere: here === i + 1,
  }));
}

/** The row's one-line summary: format, estimate, plotter, why it waits, where it is. Pure. */
export function jobMeta(job) {
  const where = job.plotter || job.target;
  return [
    job.format, `est. ${duration(job.estimate_s)}`, where ? `on ${where}` : "",
    job.waiting ? `waiting: ${job.waiting}` : "",
    job.summary || (job.done_point && !isActive(job) ? stoppedAt(job) : ""),
  ].filter(Boolean).join(" · ");
}

function stoppedAt(job) {
  const p = job.done_point;
  const layer = p.layer ? `layer ${p.layer}${p.layer_name ? ` “${p.layer_name}”` : ""} ` : "";
  return `stopped in ${layer}at X ${mm(p.x, 1)} Y ${mm(p.y, 1)}`;
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
    const row = e.target.closest("li.job[data-key]");
    if (!row || e.target.closest("input, select, label")) return;
    const button = e.target.closest("button[data-verb]");
    if (button && button.dataset.verb !== "select") actions.jobAction(row.dataset.key, button.dataset.verb);
    else actions.selectJob(row.dataset.key);
  });
  $("#queue").addEventListener("change", (e) => {
    const row = e.target.closest("li.job[data-key]");
    const layer = e.target.closest("li.layer");
    if (!row || !layer) return;
    const n = Number(layer.dataset.number);
    const job = row.dataset.key;
    if (e.target.matches("input.tick")) actions.chooseLayers(job, { tickedChange: [n, e.target.checked] });
    else if (e.target.matches("input.start")) actions.chooseLayers(job, { start: n });
    else if (e.target.matches("select.layer-pen")) {
      actions.pens.setLayerPen(job, String(n), e.target.value === "" ? null : Number(e.target.value));
    }
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
  setText($("#place-target"), job && can(job, "edit")
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
  const jobs = state.jobs.filter(inQueue);
  const movable = state.jobs.filter((j) => can(j, "move"));
  const shown = previewJob(state);
  setHidden($("#queue-empty"), jobs.length > 0);
  syncList($("#queue"), jobs, (j) => j.id,
    () => el("li", { className: "job", tabIndex: -1 },
      el("div", { className: "job-head" },
        el("button", { type: "button", className: "link name", "data-verb": "select" }),
        el("span", { className: "badge" })),
      el("div", { className: "job-meta" }),
      el("div", { className: "job-progress" }, el("progress", { max: 1 }), el("span", { className: "pct" })),
      el("ol", { className: "job-layers", "aria-label": "Layers" }),
      el("p", { className: "error job-error" }),
      el("div", { className: "row wrap actions" })),
    (node, job) => {
      node.classList.toggle("selected", shown === job);
      const name = node.querySelector(".name");
      setText(name, job.name);
      name.setAttribute("aria-pressed", String(shown === job));
      const badge = node.querySelector(".badge");
      setText(badge, jobStateText(job.state));
      badge.dataset.state = job.state;
      setText(node.querySelector(".job-meta"), jobMeta(job));
      const showProgress = (job.progress || 0) > 0 || isActive(job);
      const prog = node.querySelector(".job-progress");
      setHidden(prog, !showProgress);
      if (showProgress) {
        prog.querySelector("progress").value = job.progress || 0;
        const eta = can(job, "hold") && !state.serverLost ? ` · ${duration(job.eta_s)} left` : "";
        const drawn = Number.isFinite(job.drawn_mm) ? ` · ${length(job.drawn_mm)} drawn` : "";
        setText(prog.querySelector(".pct"), `${percent(job.progress)}${drawn}${eta}`);
      }
      renderLayers(node.querySelector(".job-layers"), job, state);
      const err = node.querySelector(".job-error");
      setText(err, job.error ? (typeof job.error === "string" ? errorText(job.error) : JSON.stringify(job.error)) : "");
      setHidden(err, !job.error);
      const buttons = jobButtons(job, movable.indexOf(job), movable.length);
      syncList(node.querySelector(".actions"), buttons, (b) => b.verb,
        (b) => el("button", { type: "button", "data-verb": b.verb, className: b.verb === "stop" ? "estop-small" : "" }, b.label),
        (btn, b) => {
          setDisabled(btn, Boolean(b.disabled));
          setAttr(btn, "aria-label", b.aria);
        });
    });
}

/** The job's layers: tick which to plot and the one to start at (when it can start or be
 * plotted again), each layer's pen (while it does not run). */
function renderLayers(list, job, state) {
  const choosing = ["start", "restart", "resume"].some((a) => can(job, a)) && (job.layers || []).length > 1;
  const pens = state.pens.list;
  const rows = layerRows(job, choosing ? layerChoice(state, job) : null, pens);
  setHidden(list, rows.length === 0 || (rows.length === 1 && pens.length === 0));
  list.classList.toggle("choosing", choosing);
  const penEditable = !isActive(job) && pens.length > 0;
  syncList(list, rows, (r) => r.key,
    (r) => el("li", { className: "layer", "data-number": r.number },
      el("input", { type: "checkbox", className: "tick", "aria-label": `Plot layer ${r.number}` }),
      el("span", { className: "swatch", "aria-hidden": "true" }),
      el("span", { className: "layer-name" }),
      el("label", { className: "start-at" },
        el("input", { type: "radio", className: "start", name: `start-${job.id}` }), el("span", {}, "start here")),
      el("progress", { max: 1 }),
      el("span", { className: "layer-info" }),
      el("select", { className: "layer-pen" }),
      el("span", { className: "layer-pen-name" })),
    (li, r) => {
      li.querySelector(".swatch").style.backgroundColor = r.colour;
      setText(li.querySelector(".layer-name"), r.name);
      const tick = li.querySelector(".tick");
      setHidden(tick, !choosing);
      if (tick.checked !== r.ticked) tick.checked = r.ticked;
      const start = li.querySelector(".start");
      setHidden(li.querySelector(".start-at"), !choosing);
      if (start.checked !== r.start) start.checked = r.start;
      setText(li.querySelector(".start-at span"), r.resumesHere ? "resume here" : "start here");
      start.setAttribute("aria-label", r.resumesHere ? `Resume in layer ${r.number}, where it stopped` : `Start at layer ${r.number}`);
      li.classList.toggle("skipped", choosing && !r.ticked);
      const bar = li.querySelector("progress");
      bar.value = r.progress;
      setHidden(bar, !isActive(job) && !r.progress);
      setAttr(bar, "aria-label", `${r.name}: ${percent(r.progress)}`);
      setText(li.querySelector(".layer-info"), r.info);
      setAttr(li, "aria-current", r.current ? "step" : null);
      const select = li.querySelector(".layer-pen");
      setHidden(select, !penEditable);
      setText(li.querySelector(".layer-pen-name"), penEditable ? "" : r.penName ? `pen “${r.penName}”` : "");
      if (penEditable) {
        select.setAttribute("aria-label", `Pen for layer ${r.number} (${r.name})`);
        syncList(select, [{ id: "", name: "no pen" }, ...pens], (pen) => pen.id,
          (pen) => el("option", { value: String(pen.id) }),
          (option, pen) => setText(option, pen.name));
        const value = r.pen === null ? "" : String(r.pen);
        if (document.activeElement !== select && select.value !== value) select.value = value;
      }
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
