// The pen library: list, add, edit, delete, odometers, reset, "try it" (servo positions),
// and the per-layer pen pickers of a job row. State lives in the one store (`state.pens`).

import { api } from "../api.js";
import { $, el, setDisabled, setHidden, setText, syncList } from "../dom.js";
import { layerTitle } from "../format.js";
import { jobActive } from "../store.js";

const SERVO_MIN = 500, SERVO_MAX = 2500; // the firmware's range for $60/$61 (µs)

/** The pen id a plotter holds now: the one the user said is loaded, else the pen of the
 * last layer the plotter's latest job drew; null when nobody knows. Pure. */
export function loadedPen(state, plotter) {
  const key = plotter || "";
  if (key in state.loadedPens) return state.loadedPens[key];
  const ran = state.jobs.filter((j) => j.started_at && (!plotter || j.plotter === plotter))
    .sort((a, b) => b.started_at - a.started_at);
  for (const job of ran) {
    const drawn = (job.layers || []).filter((l) => (l.progress || 0) > 0 && l.pen !== null && l.pen !== undefined);
    if (drawn.length) return drawn[drawn.length - 1].pen;
  }
  return null;
}

/** Before a start: the pen its first plotted layer needs, when the plotter holds another
 * (or nobody knows which): {pen, loaded, layer, layerName, plotter}; null when no pen is
 * named or it is loaded. Pure. */
export function penNeeded(state, job, choice) {
  const layers = job.layers || [];
  const first = choice && choice.ticked.length ? Math.max(choice.start || 1, choice.ticked.find((n) => n >= (choice.start || 1)) || 1) : 1;
  const layer = layers[first - 1];
  if (!layer || layer.pen === null || layer.pen === undefined) return null;
  const plotter = job.target || job.plotter || state.plotter || null;
  const loaded = loadedPen(state, state.plotterOrder.length > 1 ? plotter : null);
  if (loaded === layer.pen) return null;
  return { pen: layer.pen, loaded, layer: first, layerName: layerTitle(layer, first), plotter: state.plotterOrder.length > 1 ? plotter : "" };
}

/** A pen's name from its id (never its colour code). */
export function penName(pens, id) {
  const pen = pens.find((p) => p.id === id);
  return pen ? pen.name : `pen ${id}`;
}

/** The edit form's fields (strings) for a pen, or for a new one. Pure. */
export function penForm(pen) {
  const text = (v) => (v === null || v === undefined ? "" : String(v));
  return {
    id: pen ? pen.id : null,
    name: pen ? pen.name : "",
    colour: pen && pen.colour ? pen.colour : "#000000",
    up_us: text(pen ? pen.up_us : 1000),
    down_us: text(pen ? pen.down_us : 2000),
    speed: text(pen && pen.speed), accel: text(pen && pen.accel), reink_m: text(pen && pen.reink_m),
  };
}

/** The API body of a form, or the first thing wrong with it: { body } | { error }. Pure. */
export function penBody(form) {
  const name = form.name.trim();
  if (!name) return { error: "Name: a pen needs a name." };
  const body = { name, colour: form.colour };
  for (const [key, label] of [["up_us", "Pen up"], ["down_us", "Pen down"]]) {
    const v = Number(form[key]);
    if (!Number.isInteger(v) || v < SERVO_MIN || v > SERVO_MAX) {
      return { error: `${label}: a whole number of µs from ${SERVO_MIN} to ${SERVO_MAX}.` };
    }
    body[key] = v;
  }
  for (const [key, label] of [["speed", "Speed"], ["accel", "Acceleration"], ["reink_m", "Re-ink every"]]) {
    const raw = form[key].trim();
    if (!raw) {
      body[key] = null;
      continue;
    }
    const v = Number(raw);
    if (!Number.isFinite(v) || v <= 0) return { error: `${label}: a number above 0, or empty.` };
    body[key] = v;
  }
  return { body };
}

export async function loadPens(store) {
  try {
    const list = await api.get("/api/pens");
    store.update((st) => {
      st.pens.list = list;
    });
  } catch {
    // the pens page says so when it is opened again; nothing else depends on it
  }
}

export function createPenActions(store) {
  const run = async (what, fn) => {
    store.update((st) => {
      st.pens.busy = true;
      st.pens.error = "";
      st.pens.message = "";
    });
    try {
      const message = await fn();
      store.update((st) => {
        st.pens.message = message || "";
      });
      await loadPens(store);
      return true;
    } catch (err) {
      store.update((st) => {
        st.pens.error = `${what}: ${err.message}`;
      });
      return false;
    } finally {
      store.update((st) => {
        st.pens.busy = false;
      });
    }
  };
  const path = (id) => `/api/pens/${encodeURIComponent(id)}`;
  const named = (id) => (store.state.pens.list.find((p) => p.id === id) || { name: String(id) }).name;
  return {
    load: () => loadPens(store),
    edit(id) {
      store.update((st) => {
        st.pens.form = penForm(id === "new" ? null : st.pens.list.find((p) => p.id === id));
        st.pens.error = "";
      });
    },
    editField(key, value) {
      store.update((st) => {
        if (st.pens.form) st.pens.form[key] = value;
      });
    },
    cancel() {
      store.update((st) => {
        st.pens.form = null;
        st.pens.error = "";
      });
    },
    async save() {
      const form = store.state.pens.form;
      const { body, error } = penBody(form);
      if (error) {
        store.update((st) => {
          st.pens.error = error;
          st.pens.message = ""; // never beside an earlier "Saved"
        });
        return;
      }
      const saved = await run("Save", async () => {
        if (form.id === null) await api.post("/api/pens", body);
        else await api.patch(path(form.id), body);
        return `Saved “${body.name}”.`;
      });
      if (saved) {
        store.update((st) => {
          st.pens.form = null;
        });
      }
    },
    remove: (id) => run("Delete", async () => {
      await api.del(path(id));
      return `Deleted “${named(id)}”.`;
    }),
    reset: (id) => run("Reset", async () => {
      await api.post(`${path(id)}/reset`);
      return `“${named(id)}”: odometer reset.`;
    }),
    tryPen: (id, down) => run("Try", async () => {
      const plotter = store.state.plotter ? `?plotter=${encodeURIComponent(store.state.plotter)}` : "";
      await api.post(`${path(id)}/try${plotter}`, { down });
      return `“${named(id)}”: pen ${down ? "down" : "up"}.`;
    }),
    async setLayerPen(jobId, layer, penId) {
      try {
        const job = await api.patch(`/api/jobs/${encodeURIComponent(jobId)}`, { pens: { [layer]: penId } });
        store.update((st) => {
          st.jobs = st.jobs.map((j) => (j.id === job.id ? job : j));
        });
      } catch (err) {
        store.update((st) => {
          st.notice = { text: `Pen for layer ${layer}: ${err.message}`, error: true };
        });
      }
    },
  };
}

export function bindPens(actions) {
  $("#pens-add").addEventListener("click", () => actions.edit("new"));
  $("#pens-list").addEventListener("click", (e) => {
    const button = e.target.closest("button[data-verb]");
    const row = e.target.closest("li[data-key]");
    if (!button || !row) return;
    const id = Number(row.dataset.key);
    const verb = button.dataset.verb;
    if (verb === "edit") actions.edit(id);
    else if (verb === "delete") actions.remove(id);
    else if (verb === "reset") actions.reset(id);
    else if (verb === "try-up" || verb === "try-down") actions.tryPen(id, verb === "try-down");
  });
  const form = $("#pen-form");
  form.addEventListener("input", (e) => {
    if (e.target.name) actions.editField(e.target.name, e.target.value);
  });
  form.addEventListener("submit", (e) => {
    e.preventDefault();
    actions.save();
  });
  $("#pen-cancel").addEventListener("click", () => actions.cancel());
}

const metres = (m) => `${(m || 0).toFixed(m >= 100 ? 0 : 2)} m`;

export function renderPens(state) {
  const p = state.pens;
  const busy = p.busy, running = jobActive(state);
  setText($("#pens-message"), busy ? "Working…" : p.message);
  setText($("#pens-error"), p.error);
  setHidden($("#pens-empty"), p.list.length > 0);
  syncList($("#pens-list"), p.list, (pen) => pen.id,
    () => el("li", { className: "pen" },
      el("div", { className: "pen-head" }, el("span", { className: "swatch" }), el("strong", { className: "name" })),
      el("dl", { className: "pen-facts" },
        el("dt", {}, "Up / down"), el("dd", { className: "mono servo" }),
        el("dt", {}, "Speed"), el("dd", { className: "mono speed" }),
        el("dt", {}, "Drawn"), el("dd", { className: "mono odometer" })),
      el("div", { className: "row wrap actions" },
        el("button", { type: "button", className: "small", "data-verb": "try-up" }, "Try up"),
        el("button", { type: "button", className: "small", "data-verb": "try-down" }, "Try down"),
        el("button", { type: "button", className: "small", "data-verb": "edit" }, "Edit"),
        el("button", { type: "button", className: "small", "data-verb": "reset" }, "Reset odometer"),
        el("button", { type: "button", className: "small", "data-verb": "delete" }, "Delete"))),
    (row, pen) => {
      row.querySelector(".swatch").style.background = pen.colour || "transparent";
      setText(row.querySelector(".name"), pen.name);
      setText(row.querySelector(".servo"), `${pen.up_us} / ${pen.down_us} µs`);
      const speed = [pen.speed ? `${pen.speed} mm/min` : "program's", pen.accel ? `${pen.accel} mm/s²` : ""];
      setText(row.querySelector(".speed"), speed.filter(Boolean).join(", "));
      const due = pen.reink_m ? ` (re-ink every ${pen.reink_m} m)` : "";
      setText(row.querySelector(".odometer"), metres(pen.odometer_m) + due);
      for (const button of row.querySelectorAll("button")) {
        const trying = button.dataset.verb.startsWith("try");
        setDisabled(button, busy || (trying && running));
        if (trying) button.title = running ? "Not while a job runs" : "Set $60/$61 and move the servo";
      }
      for (const button of row.querySelectorAll("button")) {
        button.setAttribute("aria-label", `${button.textContent}: ${pen.name}`);
      }
    });
  const form = $("#pen-form");
  setHidden(form, !p.form);
  setDisabled($("#pens-add"), Boolean(p.form) || busy);
  if (p.form) {
    setText($("#pen-form-title"), p.form.id === null ? "New pen" : `Edit “${p.form.name}”`);
    for (const [key, value] of Object.entries(p.form)) {
      const input = form.elements[key];
      if (input && document.activeElement !== input && input.value !== value) input.value = value;
    }
    setDisabled($("#pen-save"), busy);
  }
}
