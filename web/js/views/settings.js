// Firmware $ settings (edit and save) and the server's own options (read-only).

import { $, el, setDisabled, setText, syncList } from "../dom.js";
import { bytes } from "../format.js";

const SERVER_LABELS = {
  version: "Version", virtual: "Virtual plotter", serial: "Serial device",
  data_dir: "Data directory", upload_limit: "Upload limit", auto_start: "Start jobs automatically",
};

const PEN_POSITIONS = new Set([60, 61]); // pen-up and pen-down servo pulses: "Try it"
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
  syncList($("#settings-body"), st.list || [], (s) => s.id, createRow,
    (row, s) => {
      setText(row.querySelector(".name"), s.name || `$${s.id}`);
      setText(row.querySelector(".desc"), s.description || "");
      setText(row.querySelector(".unit"), s.unit && s.unit !== "bool" && s.unit !== "mask" ? s.unit : "");
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
    el("td", { className: "mono" }, `$${s.id}`),
    el("td", {}, label, el("div", { className: "hint desc" })),
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
