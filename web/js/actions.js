// Everything the page does to the server. Each action updates the one state object;
// the views render from it.

import { api, ApiError, uploadJob } from "./api.js";
import { LOG_LIMIT } from "./views/console.js";
import { askPermission, notifyJob } from "./notify.js";
import { loadPens } from "./views/pens.js";
import { buildGeometry } from "./preview-data.js";
import { reduce, withPlacement } from "./reducer.js";
import { holdAction, previewJob } from "./store.js";

const POLL_MS = 2000; // REST polling while the WebSocket is down
const SELECTED_KEY = "plotbridge.selectedJob"; // this tab's selected job (sessionStorage)
const asList = (data, key) => (Array.isArray(data) ? data : (data && data[key]) || []);
const sameId = (a, b) => String(a) === String(b);

/** The API's placement fields from the form's state. */
export function placementFields(p) {
  const out = { margin: p.margin, fit: p.fit, rotate: p.rotate, scale: p.scale, dx: p.dx, dy: p.dy };
  out.paper = !p.paper ? null : p.landscape ? `${p.paper}-landscape` : p.paper; // null: the work area
  return out;
}

/** Placement as upload form fields. */
function appendPlacement(form, placement) {
  for (const [k, v] of Object.entries(placementFields(placement))) {
    if (v !== null) form.append(k, String(v));
  }
}

/** The upload form's import options (pen dialect, fills, font) as form fields. */
function appendImportOptions(form) {
  const options = document.getElementById("import-options");
  if (!options) return;
  for (const [key, value] of new FormData(options)) {
    if (value !== "") form.append(key, value);
  }
}

/** Errors of a refused upload as a list to show, by line. */
export function uploadErrors(err) {
  const d = err.detail;
  if (d && Array.isArray(d.errors)) {
    return d.errors.map((e, i) => ({ key: i, line: e.line, message: String(e.message ?? "") }));
  }
  return [];
}

function uploadMessage(err) {
  if (err.status === 413) return "Refused: too large";
  if (err.status === 415) return "Refused: not a format plotbridge accepts";
  if (err.status === 422) {
    const n = uploadErrors(err).length;
    return n > 1 ? `Refused: ${n} errors` : "Refused";
  }
  return `Failed: ${err.message}`;
}

/** A random id for this page: it tells this page's stops from other browsers'. */
function newPageId() {
  const bytes = crypto.getRandomValues(new Uint8Array(12));
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}

function storedSelection() {
  try {
    return sessionStorage.getItem(SELECTED_KEY);
  } catch {
    return null;
  }
}

export function createActions(store, socket, estop) {
  const s = store.state;
  s.pageId = newPageId();
  s.selectedJobId = storedSelection();
  let uploadSeq = 0;
  let placementTimer = null;
  let pollTimer = null;

  /** Apply an incoming message (or a REST answer shaped as one) through the reducer. */
  function apply(msg) {
    store.update((st) => {
      Object.assign(st, reduce(st, msg));
    });
  }

  // Socket messages heard so far, by kind. A REST answer that crossed a socket message of
  // its kind on the way is dropped: the socket delivers every change, and the older answer
  // applied last would show a stale state until the next change (an idle board may not
  // change for hours).
  const heard = { machine: 0, jobs: 0 };
  const unchanged = (kind) => {
    const at = heard[kind];
    return () => heard[kind] === at;
  };

  /** Over REST: the machine and the jobs. A network failure while the socket is down
   * means the server is unreachable: the header says so instead of stale values. */
  function resync() {
    loadMachine(() => store.update((st) => {
      st.serverLost = false;
    })).catch((err) => {
      if (err.status === 0 && s.socket.status !== "open") {
        store.update((st) => {
          st.serverLost = true;
        });
      }
    });
    loadJobs().catch(() => {});
  }

  const fail = (field) => (err) => {
    if (err instanceof ApiError && err.status === 401) return;
    store.update((st) => {
      st[field] = err.message;
    });
  };
  const clear = (field) => store.update((st) => {
    st[field] = "";
  });

  /** A machine report: kept per plotter; the selected one (the first by default) is shown. */
  function onMachine(msg) {
    const wasConnected = Boolean(s.machine && s.machine.connected);
    apply(msg);
    // the board's settings (and the work area) are read again when it (re)connects
    if (s.machine && s.machine.connected && !wasConnected && s.view === "app") loadSettings();
  }

  const setMachine = (m) => onMachine({ type: "machine", machine: m });

  /** The selected plotter's machine over REST; `answered` runs on any answer. */
  async function loadMachine(answered = () => {}) {
    const fresh = unchanged("machine");
    const m = await api.get(machinePath());
    answered();
    if (fresh()) setMachine(m);
  }

  /** A board verb's path: the selected plotter's when there are several. */
  function machinePath(verb = "") {
    const several = s.plotterOrder.length > 1 && s.plotter;
    const base = several ? `/api/plotters/${encodeURIComponent(s.plotter)}/machine` : "/api/machine";
    return verb ? `${base}/${verb}` : base;
  }

  function upsertJob(job) {
    notifyJob(s.jobs.find((j) => sameId(j.id, job.id)), job);
    apply({ type: "job", job });
    ensurePreview();
  }

  async function loadJobs() {
    const fresh = unchanged("jobs");
    const jobs = asList(await api.get("/api/jobs"), "jobs");
    if (fresh()) apply({ type: "jobs", jobs });
    ensurePreview();
  }

  /** A preview's version: re-fetch when a re-import changed the job. */
  const previewVersion = (job) => JSON.stringify([job.lines_total, job.bounds, job.placement]);

  async function ensurePreview() {
    const job = previewJob(s);
    if (!job) return;
    const version = previewVersion(job);
    const have = s.previews[job.id];
    if (have && have.version === version) return;
    s.previews[job.id] = { version, geom: have && have.geom }; // the old one shows meanwhile
    let entry;
    try {
      const data = await api.get(`/api/jobs/${encodeURIComponent(job.id)}/preview`);
      entry = { version, geom: buildGeometry(data) };
    } catch (err) {
      entry = { version, error: err.message };
    }
    store.update((st) => {
      const current = st.previews[job.id];
      if (current && current.version !== version) return; // a newer re-import is loading
      // Only the shown job's preview is kept: a big one takes megabytes.
      st.previews = { [job.id]: entry };
    });
  }

  /** Reads the board's settings; unsaved edits survive unless `discardEdits` (the Reload button). */
  async function loadSettings(discardEdits = false) {
    store.update((st) => {
      st.settings.busy = true;
      st.settings.error = "";
    });
    try {
      const data = await api.get(machinePath("settings"));
      store.update((st) => {
        st.settings.list = asList(data, "settings");
        if (discardEdits) st.settings.edits = {};
        st.settings.rowErrors = {};
        st.settings.message = "";
      });
    } catch (err) {
      store.update((st) => {
        st.settings.error = `Could not read the settings: ${err.message}`;
      });
    } finally {
      store.update((st) => {
        st.settings.busy = false;
      });
    }
  }

  async function machineCall(path, body) {
    clear("controlError");
    try {
      await api.post(path, body);
      return true;
    } catch (err) {
      fail("controlError")(err);
      store.update((st) => {
        st.notice = { text: err.message, error: true };
      });
      return false;
    }
  }

  /** Select a job: its preview and placement show, also after a reload of this tab. */
  function select(id) {
    try {
      sessionStorage.setItem(SELECTED_KEY, String(id));
    } catch {
      // storage may be off: the selection then lasts until a reload
    }
    store.update((st) => {
      st.selectedJobId = id;
      Object.assign(st, withPlacement(st));
    });
  }

  /** Home and unlock clear the stopped state: the panel goes once they succeed. */
  async function clearing(path) {
    if (await machineCall(path)) estop.dismiss();
  }

  const actions = {
    setMachine,
    upsertJob,
    loadJobs,
    loadSettings,

    /** Everything over REST; resolves when the machine's answer has been applied. */
    loadAll() {
      const machine = loadMachine().catch(() => {});
      loadJobs().catch(() => {});
      api.get("/api/server").then((d) => store.update((st) => {
        st.server = d;
      })).catch(() => {});
      loadPens(store);
      api.get("/api/patterns").then((d) => store.update((st) => {
        st.patterns = asList(d, "patterns");
      })).catch(() => {});
      return machine;
    },

    async login(token) {
      store.update((st) => {
        st.login = { busy: true, error: "" };
      });
      try {
        await api.post("/api/login", { token });
        store.update((st) => {
          st.login = { busy: false, error: "" };
        });
        actions.enterApp();
      } catch (err) {
        store.update((st) => {
          st.login = { busy: false, error: err.status === 401 ? "Wrong token." : err.message };
        });
      }
    },

    async logout() {
      try {
        await api.post("/api/logout");
      } finally {
        actions.leaveApp();
      }
    },

    enterApp() {
      store.update((st) => {
        st.view = "app";
      });
      socket.start();
      actions.loadAll();
    },

    leaveApp() {
      socket.stop();
      clearInterval(pollTimer);
      store.update((st) => {
        st.view = "login";
        st.estop = null;
      });
    },

    // ---- WebSocket ----

    onSocketMessage(msg) {
      if (msg.type === "machine") heard.machine += 1;
      else if (["job", "jobs", "job_deleted", "queue"].includes(msg.type)) heard.jobs += 1;
      if (msg.type === "machine") onMachine(msg);
      else if (msg.type === "job") upsertJob(msg.job && typeof msg.job === "object" ? msg.job : msg);
      else if (["jobs", "job_deleted", "queue", "stopped", "pens"].includes(msg.type)) {
        apply(msg);
        ensurePreview();
      } else if (msg.type === "log") actions.appendLog(msg.direction || "rx", msg.line ?? "");
      else if (msg.type === "ack" && msg.command === "estop") estop.onSocketAck();
      else if (msg.type === "error" && msg.command === "command" && msg.confirm) {
        actions.confirmCommand(msg.line, msg.detail);
      } else if (msg.type === "error") {
        store.update((st) => {
          const detail = msg.detail ?? msg.message ?? "error from the server";
          const text = typeof detail === "string" ? detail : new ApiError(0, detail).message;
          if (msg.command === "command") st.commandError = text;
          else st.notice = { text: `${msg.command ?? "command"}: ${text}`, error: true };
        });
      }
    },

    onSocketStatus(status) {
      if (status.code === 4401) {
        actions.leaveApp();
        return;
      }
      const wasOpen = s.socket.status === "open";
      const open = status.status === "open";
      store.update((st) => {
        st.socket = status;
        if (open) st.serverLost = false;
      });
      // Resynchronize after a reconnect: messages may have been missed. While the
      // socket is down, poll over REST so the page does not show a stale state (and
      // knows at once whether the server is unreachable).
      if (open !== wasOpen) resync();
      clearInterval(pollTimer);
      pollTimer = open ? null : setInterval(resync, POLL_MS);
    },

    appendLog(direction, line) {
      store.update((st) => {
        st.log.push({ seq: ++st.logSeq, direction, line: String(line) });
        if (st.log.length > LOG_LIMIT) st.log.splice(0, st.log.length - LOG_LIMIT);
      });
    },

    // ---- jobs ----

    uploadFile(file) {
      const id = `u${++uploadSeq}`;
      const record = { id, name: file.name, loaded: 0, total: file.size, status: "uploading", message: "", errors: [] };
      store.update((st) => {
        st.uploads.unshift(record);
      });
      const form = new FormData();
      form.append("file", file, file.name);
      form.append("name", file.name);
      appendPlacement(form, s.placement);
      appendImportOptions(form);
      const progress = (loaded, total) => store.update(() => {
        Object.assign(record, { loaded, total, status: loaded >= total ? "processing" : "uploading" });
      });
      uploadJob(form, progress).then(
        (job) => {
          store.update(() => {
            Object.assign(record, { status: "done", message: "added to the queue" });
          });
          select(job.id);
          upsertJob(job);
          setTimeout(() => actions.dismissUpload(id), 4000);
        },
        (err) => store.update(() => {
          Object.assign(record, { status: "failed", message: uploadMessage(err), errors: uploadErrors(err) });
        }),
      );
    },

    async addPattern(name) {
      const id = `u${++uploadSeq}`;
      const record = { id, name, loaded: 0, total: 0, status: "processing", message: "", errors: [] };
      store.update((st) => {
        st.uploads.unshift(record);
      });
      const form = new FormData();
      form.append("pattern", name);
      form.append("name", name);
      appendPlacement(form, s.placement);
      try {
        const job = await uploadJob(form, () => {});
        store.update(() => {
          Object.assign(record, { status: "done", message: "added to the queue" });
        });
        select(job.id);
        upsertJob(job);
        setTimeout(() => actions.dismissUpload(id), 4000);
      } catch (err) {
        store.update(() => {
          Object.assign(record, { status: "failed", message: uploadMessage(err), errors: uploadErrors(err) });
        });
      }
    },

    dismissUpload(id) {
      store.update((st) => {
        st.uploads = st.uploads.filter((u) => u.id !== id);
      });
    },

    clearFailedUploads() {
      store.update((st) => {
        st.uploads = st.uploads.filter((u) => u.status !== "failed");
      });
    },

    selectJob(id) {
      const job = s.jobs.find((j) => sameId(j.id, id));
      if (!job) return;
      select(job.id);
      store.update((st) => {
        st.placementError = "";
      });
      ensurePreview();
    },

    placementChanged(patch) {
      store.update((st) => {
        st.placement = { ...st.placement, ...patch }; // only the fields edited
        st.placementDirty = true;
      });
      clearTimeout(placementTimer);
      placementTimer = setTimeout(actions.applyPlacement, 300);
    },

    /** The offset that puts the drawing's lower-left corner where the pen is now. */
    placeHere() {
      const job = previewJob(s);
      const m = s.machine;
      if (!job || !job.bounds || !m || !m.position) return;
      const p = s.placement;
      const round = (v) => Math.round(v * 100) / 100;
      actions.placementChanged({
        dx: round(p.dx + m.position.x - job.bounds.min_x), dy: round(p.dy + m.position.y - job.bounds.min_y),
      });
    },

    /** Re-import the shown queued job with the form's placement, then reload its preview.
     * A refused change puts back what the job really has (and says why). */
    async applyPlacement() {
      const job = previewJob(s);
      if (!job || job.state !== "queued") return;
      const sent = s.placement;
      try {
        const updated = await api.patch(`/api/jobs/${encodeURIComponent(job.id)}`, {
          placement: placementFields(sent),
        });
        clear("placementError");
        store.update((st) => {
          if (st.placement === sent) st.placementDirty = false; // not edited meanwhile
        });
        if (updated && updated.id !== undefined) upsertJob(updated);
        else await loadJobs();
      } catch (err) {
        const errors = uploadErrors(err);
        store.update((st) => {
          st.placementError = errors.length ? errors.map((e) => e.message).join("; ") : err.message;
          st.placementDirty = false;
          st.placementKey = null;
          Object.assign(st, withPlacement(st));
        });
      }
    },

    async jobVerb(id, verb) {
      const job = s.jobs.find((j) => sameId(j.id, id));
      if (!job) return;
      if (verb === "select") return actions.selectJob(id);
      const path = `/api/jobs/${encodeURIComponent(job.id)}`;
      try {
        if (verb === "delete") {
          await api.del(path);
          store.update((st) => {
            st.jobs = st.jobs.filter((j) => j !== job);
            delete st.previews[job.id];
          });
          return;
        }
        if (verb === "up" || verb === "down") {
          const waiting = s.jobs.filter((j) => j.state === "queued");
          const position = waiting.indexOf(job) + (verb === "up" ? -1 : 1);
          await api.post(`${path}/move`, { position });
          await loadJobs();
          return;
        }
        if (verb === "start" || verb === "resume" || verb === "restart") askPermission(); // pen changes and job ends notify
        const updated = await api.post(`${path}/${verb}`);
        if (updated && updated.id !== undefined) upsertJob(updated);
        if (verb === "start" || verb === "restart") {
          select(job.id);
          store.update((st) => {
            st.estop = null;
          });
        }
      } catch (err) {
        store.update((st) => {
          st.notice = { text: `${verb} “${job.name}”: ${err.message}`, error: true };
        });
      }
    },

    // ---- resume from a point ----
    pickResumePoint(jobId, vertex) {
      store.update((st) => {
        st.resumePick = { jobId, x: vertex.x, y: vertex.y };
      });
    },

    setResumeOverlap(value) {
      const mm = Number(value);
      store.update((st) => {
        st.resumeOverlap = Number.isFinite(mm) && mm >= 0 ? mm : 0;
      });
    },

    /** Resume a job from its picked point (with the overlap), else where it stopped;
     * `home`: $H first. */
    async resumeFromPoint(id, home) {
      const target = s.jobs.find((j) => sameId(j.id, id));
      if (!target) return;
      const pick = s.resumePick && sameId(s.resumePick.jobId, id) ? s.resumePick : null;
      const body = pick ? { from: { x: pick.x, y: pick.y }, overlap: s.resumeOverlap } : {};
      if (home) body.home = true;
      try {
        const updated = await api.post(`/api/jobs/${encodeURIComponent(target.id)}/resume`, body);
        if (updated && updated.id !== undefined) upsertJob(updated);
        store.update((st) => {
          st.resumePick = null;
          st.selectedJobId = target.id;
          st.estop = null;
        });
      } catch (err) {
        store.update((st) => {
          st.notice = { text: `resume “${target.name}”: ${err.message}`, error: true };
        });
      }
    },

    // ---- plotters ----
    selectPlotter(name) {
      store.update((st) => {
        st.plotter = name;
        if (st.plotters[name]) {
          st.machineSeq += 1;
          st.machine = { ...st.plotters[name], seq: st.machineSeq };
        }
      });
      loadSettings();
    },
    estopPlotter(name) {
      if (!socket.send({ type: "estop", plotter: name })) {
        api.post(`/api/plotters/${encodeURIComponent(name)}/machine/estop`).catch(() => {});
      }
    },
    estopAll() {
      if (!socket.send({ type: "estop", all: true })) api.post("/api/estop").catch(() => {});
    },
    /** The big Hold/Continue button: `!` or `~` by the WebSocket, REST if it is closed. */
    holdOrContinue() {
      const what = holdAction(s);
      if (!what) return;
      const type = what === "hold" ? "pause" : "resume";
      if (!socket.send({ type, plotter: s.plotter })) machineCall(machinePath(what));
    },
    holdPlotter(name) {
      const job = s.jobs.find((j) => j.plotter === name && j.state === "running");
      if (job) api.post(`/api/jobs/${encodeURIComponent(job.id)}/pause`).then(upsertJob).catch(() => {});
    },

    // ---- machine ----

    home: () => clearing(machinePath("home")),
    unlock: () => clearing(machinePath("unlock")),
    pen: (down) => machineCall(machinePath("pen"), { down }),
    motors: (enabled) => machineCall(machinePath("motors"), { enabled }),
    jog: (ux, uy) => machineCall(machinePath("jog"), { dx: ux * s.jog.step, dy: uy * s.jog.step, feed: s.jog.feed }),
    setJog(patch) {
      store.update((st) => {
        Object.assign(st.jog, patch);
      });
    },
    dismissEstop: () => estop.dismiss(),

    bannerAction(action, id) {
      if (action === "reconnect") socket.reconnectNow();
      else if (action === "home") actions.home();
      else if (action === "unlock") actions.unlock();
      else if (action === "resume") {
        const job = s.jobs.find((j) => j.state === "paused");
        if (job) actions.jobVerb(job.id, "resume");
        else if (!socket.send({ type: "resume", plotter: s.plotter })) machineCall(machinePath("command"), { line: "~" });
      } else if (action === "resume-job") actions.jobVerb(id, "resume");
    },

    // ---- settings ----

    editSetting(id, value) {
      store.update((st) => {
        const original = (st.settings.list || []).find((x) => String(x.id) === id);
        if (original && String(original.value) === value) delete st.settings.edits[id];
        else st.settings.edits[id] = value;
      });
    },

    /** "Try it" for a pen position ($60 up, $61 down): the value (as edited) is written
     * (the server checks its range) and the pen moved there, so the servo shows it live. */
    async tryPen(id) {
      const entry = (s.settings.list || []).find((x) => String(x.id) === id);
      const value = Number(id in s.settings.edits ? s.settings.edits[id] : entry && entry.value);
      store.update((st) => {
        st.settings.busy = true;
        st.settings.error = "";
      });
      try {
        await api.put(machinePath("settings"), { settings: { [id]: value } });
        await api.post(machinePath("pen"), { down: id === "61" });
        store.update((st) => {
          if (entry) entry.value = value;
          delete st.settings.edits[id];
          st.settings.message = `Pen moved ${id === "61" ? "down" : "up"} with $${id}=${value} (saved).`;
        });
      } catch (err) {
        store.update((st) => {
          st.settings.error = `Try $${id}: ${err.message}`;
        });
      } finally {
        store.update((st) => {
          st.settings.busy = false;
        });
      }
    },

    async saveSettings() {
      const edits = s.settings.edits;
      const body = {};
      const rowErrors = {};
      for (const [id, value] of Object.entries(edits)) {
        const n = Number(value);
        if (value.trim() === "" || !Number.isFinite(n)) rowErrors[id] = "not a number";
        else body[id] = n;
      }
      if (Object.keys(rowErrors).length) {
        store.update((st) => {
          st.settings.rowErrors = rowErrors;
          st.settings.error = `Not a number: ${Object.keys(rowErrors).map((id) => `$${id}`).join(", ")}`;
        });
        return;
      }
      store.update((st) => {
        st.settings.busy = true;
        st.settings.error = "";
        st.settings.rowErrors = {};
      });
      try {
        await api.put(machinePath("settings"), { settings: body });
        // The board acknowledged every line. Show those values rather than re-reading:
        // the server's copy of the settings is only refreshed on (re)connect for now.
        store.update((st) => {
          for (const entry of st.settings.list || []) {
            if (String(entry.id) in body) entry.value = body[String(entry.id)];
          }
          st.settings.edits = {};
          st.settings.busy = false;
          st.settings.message = `Saved ${Object.keys(body).length} setting(s) to the board.`;
        });
      } catch (err) {
        store.update((st) => {
          st.settings.busy = false;
          st.settings.error = err.status === 409 ? "Settings cannot be changed while a job runs." : `Save failed: ${err.message}`;
        });
      }
    },

    // ---- console ----

    async sendCommand(line, confirm = false) {
      clear("commandError");
      if (socket.send({ type: "command", line, plotter: s.plotter, confirm })) return; // the log shows tx and the answer
      actions.appendLog("tx", line);
      try {
        const data = await api.post(machinePath("command"), { line, confirm });
        for (const r of asList(data, "responses")) actions.appendLog("rx", r);
      } catch (err) {
        if (err.status === 428 && !confirm) actions.confirmCommand(line, err.message);
        else fail("commandError")(err);
      }
    },

    // A line that wedges or wipes the board ($SLP, $RST=): the server said what it does.
    confirmCommand(line, what) {
      if (window.confirm(`${what}\n\nSend ${line}?`)) actions.sendCommand(line, true);
      else store.update((st) => { st.commandError = `${line} not sent`; });
    },
  };
  return actions;
}
