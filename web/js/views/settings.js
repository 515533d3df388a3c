// Firmware $ settings (edit and save) and the server's own options (read-only).

import { $, el, setDisabled, setText, syncList } from "../dom.js";
import { bytes } from "../format.js";

const SERVER_LABELS = {
  version: "Version", virtual: "Virtual plotter", serial: "Serial device",
  data_dir: "Data directory", upload_limit: "Upload limit", auto_start: "Start jobs automatically",
};

export function bindSettings(actions) {
  $("#settings-body").addEventListener("input", (e) => {
    const input = e.target.closest("input[data-id]");
    if (input) actions.editSetting(input.dataset.id, input.value);
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
  $("#settings-save").textContent = changed ? `Save ${changed} change${changed > 1 ? "s" : ""}` : "Save changes";
  syncList($("#settings-body"), st.list || [], (s) => s.id,
    (s) => {
      const inputId = `setting-${s.id}`;
      return el("tr", {},
        el("td", { className: "mono" }, `$${s.id}`),
        el("td", {}, el("label", { for: inputId, className: "name" }), el("div", { className: "hint desc" })),
        el("td", { className: "value" },
          el("input", { id: inputId, "data-id": s.id, inputmode: "decimal", className: "mono", size: 8 }),
          el("span", { className: "unit" })));
    },
    (row, s) => {
      setText(row.querySelector(".name"), s.name || `$${s.id}`);
      setText(row.querySelector(".desc"), s.description || "");
      setText(row.querySelector(".unit"), s.unit || "");
      const input = row.querySelector("input");
      const key = String(s.id);
      const value = key in st.edits ? st.edits[key] : String(s.value);
      if (document.activeElement !== input && input.value !== value) input.value = value;
      row.classList.toggle("edited", key in st.edits);
      const err = (st.rowErrors || {})[key];
      input.setAttribute("aria-invalid", err ? "true" : "false");
      input.title = err || "";
    });
  const server = state.server || {};
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
