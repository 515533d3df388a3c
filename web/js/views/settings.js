// Firmware $ settings (edit and save) and the server's own options (read-only).

import { $, el, setDisabled, setText, syncList } from "../dom.js";
import { bytes } from "../format.js";

const SERVER_LABELS = {
  version: "Version", virtual: "Virtual plotter", serial: "Serial device",
  data_dir: "Data directory", upload_limit: "Upload limit", auto_start: "Start jobs automatically",
};

const PEN_POSITIONS = new Set([60, 61]); // pen-up and pen-down servo pulses: "Try it"
// settings_meta.GROUPS: what a plotter user means by each setting, in this order
const GROUPS = [
  ["motion", "Motion"], ["pen", "Pen"], ["switches", "Switches and homing"], ["area", "Work area"],
  ["board", "Electronics"], ["other", "Not used by a pen plotter (spindle, probe, laser, Z)"],
];

/** The rows to show: each group's heading, then its settings (in the board's order);
 * the "other" group only when asked. Pure. */
export function settingRows(list, showAll) {
  const out = [];
  for (const [group, title] of GROUPS) {
    if (group === "other" && !showAll) continue;
    const rows = (list || []).filter((s) => (s.group || "other") === group);
    if (!rows.length) continue;
    out.push({ key: `g:${group}`, heading: title });
    for (const s of rows) out.push({ key: String(s.id), setting: s });
  }
  return out;
}
const MASK_BITS = ["X", "Y"]; // bit 0, bit 1 of the mask settings (settings_meta.MASK_BITS)

/** A row's value as the board takes it: the number typed, 0/1 for a switch, the sum of
 * the ticked bits for a mask. */
function rowValue(row, kind) {
  if (kind === "bool") return row.querySelector("input").checked ? "1" : "0";
  if (kind === "mask") {
    let v = 0;
    for (const box of row.querySelectorAll("input[data-bit]")) if (box.checked) v |= 1 << Number(box.dataset.bit);
    return String(v);
  }
  return row.querySelector("input").value;
}

export function bindSettings(actions) {
  const body = $("#settings-body");
  const edited = (e) => {
    const row = e.target.closest("tr[data-kind]");
    if (row && e.target.matches("input")) actions.editSetting(row.dataset.key, rowValue(row, row.dataset.kind));
  };
  body.addEventListener("input", edited);
  body.addEventListener("change", edited);
  body.addEventListener("click", (e) => {
    const button = e.target.closest("button[data-try]");
    if (button) actions.tryPen(button.dataset.try);
  });
  $("#settings-save").addEventListener("click", () => actions.saveSettings());
  $("#settings-all").addEventListener("change", (e) => actions.showAllSettings(e.target.checked));
  $("#webhooks-form").addEventListener("input", (e) => actions.editWebhookDraft(e.target.value));
  $("#webhooks-form").addEventListener("submit", (e) => {
    e.preventDefault();
    const urls = $("#webhooks-urls").value.split("\n").map((u) => u.trim()).filter(Boolean);
    actions.saveWebhooks(urls);
  });
  $("#settings-reload").addEventListener("click", () => actions.loadSettings(true));
}

export function renderSettings(state) {
  const st = state.settings;
  setText($("#settings-message"), st.busy ? "Working…" : st.message);
  setText($("#settings-error"), st.error);
  const changed = Object.keys(st.edits).length;
  setDisabled($("#settings-save"), st.busy || changed === 0);
  for (const button of document.querySelectorAll("#settings-body button[data-try]")) setDisabled(button, st.busy);
  $("#settings-save").textContent = changed ? `Save ${changed} change${changed > 1 ? "s" : ""}` : "Save changes";
  const hidden = (st.list || []).filter((s) => (s.group || "other") === "other").length;
  setText($("#settings-all-count"), hidden ? `(${hidden})` : "");
  syncList($("#settings-body"), settingRows(st.list, state.settingsAll), (r) => r.key,
    (r) => (r.heading ? el("tr", { className: "group-head" }, el("th", { colSpan: 2, scope: "colgroup" }, r.heading)) : createRow(r.setting)),
    (row, r) => {
      if (r.heading) return;
      const s = r.setting;
      setText(row.querySelector(".name"), s.name || `$${s.id}`);
      setText(row.querySelector(".desc"), s.description || "");
      setText(row.querySelector(".unit"), s.unit && s.unit !== "bool" && s.unit !== "mask" && s.unit !== "enum" ? s.unit : "");
      setText(row.querySelector(".range"), s.range ? s.range.text : "");
      const key = String(s.id);
      const value = key in st.edits ? st.edits[key] : String(s.value);
      showValue(row, row.dataset.kind, value);
      row.classList.toggle("edited", key in st.edits);
      const err = (st.rowErrors || {})[key];
      for (const input of row.querySelectorAll("input")) {
        input.setAttribute("aria-invalid", err ? "true" : "false");
        input.title = err || "";
      }
    });
  renderWebhooks(state.webhooks);
  const server = state.server || {};
  renderServer(server);
}

/** A row for one setting: a switch for on/off, a box per bit for masks, a number else. */
function createRow(s) {
  const inputId = `setting-${s.id}`;
  const kind = (s.range && s.range.kind) || "number";
  let value;
  if (kind === "bool") {
    value = el("input", { id: inputId, type: "checkbox" });
  } else if (kind === "mask") {
    value = el("span", { className: "bits", id: inputId, role: "group" }, MASK_BITS.map((axis, bit) =>
      el("label", { className: "check" }, el("input", { type: "checkbox", "data-bit": bit }), ` ${axis}`)));
  } else {
    const r = s.range || {};
    value = el("input", {
      id: inputId, inputmode: "decimal", className: "mono", size: 8, readOnly: kind === "fixed",
      type: "number", step: "any", min: r.min, max: r.max,
    });
  }
  const label = kind === "mask" ? el("span", { className: "name" }) : el("label", { for: inputId, className: "name" });
  return el("tr", { "data-kind": kind },
    el("td", {}, label, el("span", { className: "grbl mono" }, `$${s.id}`), el("div", { className: "hint desc" })),
    el("td", { className: "value" }, value, el("span", { className: "unit" }), el("span", { className: "range hint" }),
      PEN_POSITIONS.has(s.id) ? el("button", { type: "button", className: "small", "data-try": s.id,
        title: "Save this value and move the pen there" }, "Try it") : null));
}

function showValue(row, kind, value) {
  if (kind === "bool") {
    const box = row.querySelector("input");
    const want = Number(value) !== 0;
    if (box.checked !== want) box.checked = want;
  } else if (kind === "mask") {
    for (const box of row.querySelectorAll("input[data-bit]")) {
      const want = (Number(value) & (1 << Number(box.dataset.bit))) !== 0;
      if (box.checked !== want) box.checked = want;
    }
  } else {
    const input = row.querySelector("input");
    if (document.activeElement !== input && input.value !== value) input.value = value;
  }
}

function renderServer(server) {
  syncList($("#server-info"), Object.keys(server).flatMap((k) => [`dt:${k}`, `dd:${k}`]), (k) => k,
    (k) => el(k.slice(0, 2)),
    (node, k) => {
      const name = k.slice(3);
      const v = server[name];
      setText(node, k.startsWith("dt") ? SERVER_LABELS[name] || name
        : typeof v === "boolean" ? (v ? "yes" : "no") : v === null || v === undefined ? "–"
          : name === "upload_limit" ? bytes(v) : String(v));
    });
}

function renderWebhooks(w) {
  const data = w.data || { urls: [], fixed: [], webhooks: [] };
  const area = $("#webhooks-urls");
  const text = w.draft ?? data.urls.join("\n");
  if (document.activeElement !== area && area.value !== text) area.value = text;
  setText($("#webhooks-message"), w.busy ? "Saving…" : w.message);
  setText($("#webhooks-error"), w.error);
  setDisabled($("#webhooks-save"), w.busy);
  setText($("#webhooks-fixed"), data.fixed.length ? `Also sent to (from the server's command line): ${data.fixed.join(", ")}` : "");
  syncList($("#webhooks-status"), data.webhooks, (h) => h.url,
    () => el("li", {}, el("span", { className: "url mono" }), el("span", { className: "hint counts" })),
    (li, h) => {
      setText(li.querySelector(".url"), h.url);
      setText(li.querySelector(".counts"), ` ${h.delivered} delivered, ${h.queued} queued, ${h.dropped} dropped${h.last_error ? ` · last error: ${h.last_error}` : ""}`);
    });
}
