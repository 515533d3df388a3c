// Jobs: uploads and patterns, selection, placement, the actions a job offers (with the
// layers to plot and the pen to load first), resume from a picked point, history.

import { ApiError, api, uploadJob } from "../api.js";
import { actionMessage, actionRequest, can, isResumable, resumeChoice } from "../job-actions.js";
import { askPermission } from "../notify.js";
import { layerOfLine, nearestOnStroke } from "../preview-data.js";
import { withPlacement } from "../reducer.js";
import { previewJob } from "../store.js";
import { penNeeded } from "../views/pens.js";
import { sameId } from "./core.js";

/** The API's placement fields from the form's state. */
export function placementFields(p) {
  const out = { margin: p.margin, fit: p.fit, rotate: p.rotate, scale: p.scale, dx: p.dx, dy: p.dy };
  out.paper = !p.paper ? null : p.landscape ? `${p.paper}-landscape` : p.paper; // null: the work area
  return out;
}

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

/** A job's layer choice (every layer ticked, from the first) unless the user changed it.
 * A stopped or interrupted job's starts where it stopped (`start` null) with the layers it
 * was plotting. */
export function layerChoice(state, job) {
  const have = state.layerChoice[job.id];
  if (have) return have;
  const count = (job.layers || []).length;
  const plotted = job.plot_layers && job.plot_layers.length ? job.plot_layers : null;
  const ticked = plotted || Array.from({ length: count }, (_, i) => i + 1);
  if (isResumable(job)) return { ticked, start: null };
  return { ticked, start: plotted ? plotted[0] : 1 };
}

/** Job actions over the WebSocket (`job_action`), REST while it is down. The server runs one
 * client's job actions in order, so its answers come in the order they were asked. An
 * action the socket has not answered in ANSWER_MS (a socket that hangs without closing)
 * goes over REST. */
const ANSWER_MS = 5000;

function createJobChannel({ socket, core }) {
  const pending = [];

  function overRest(p) {
    const i = pending.indexOf(p);
    if (i < 0) return; // answered meanwhile
    pending.splice(i, 1);
    clearTimeout(p.timer);
    viaRest(p.req, true).then(p.resolve, p.reject);
  }

  function viaRest(req, retried = false) {
    const call = req.method === "DELETE" ? api.del(req.path) : api.post(req.path, req.body);
    if (!retried) return call;
    // sent on a socket that closed or hung before it answered: the server may have done it; then
    // the lifecycle refuses this second copy (409, 404), and the job shows what happened
    return call.catch((err) => {
      if (err.status === 409 || err.status === 404) return core.loadJobs().then(() => null);
      throw err;
    });
  }

  return {
    /** `action` on `job`: resolves with the job as the server answered (null: gone). */
    send(job, action, opts) {
      const req = actionRequest(job, action, opts);
      if (!socket.send(actionMessage(job, action, opts))) return viaRest(req);
      return new Promise((resolve, reject) => {
        const p = { action, id: String(job.id), req, resolve, reject };
        p.timer = setTimeout(() => overRest(p), ANSWER_MS);
        pending.push(p);
      });
    },
    /** The socket's `ack` or `error` of a `job_action`. */
    answered(msg) {
      const i = msg.type === "ack"
        ? pending.findIndex((p) => p.action === msg.action && (!msg.job || p.id === String(msg.job.id)))
        : msg.action ? pending.findIndex((p) => p.action === msg.action) : pending.length - 1; // refused unread: the last
      if (i < 0) return;
      const [p] = pending.splice(i, 1);
      clearTimeout(p.timer);
      if (msg.type === "ack") p.resolve(msg.job || null);
      else p.reject(new ApiError(msg.status || 0, msg.detail ?? "refused"));
    },
    /** The socket closed: what it did not answer goes over REST. */
    down() {
      for (const p of [...pending]) overRest(p);
    },
  };
}

export function jobActions({ store, estop, socket, core, all }) {
  const s = store.state;
  let uploadSeq = 0;
  let placementTimer = null;
  const channel = createJobChannel({ socket, core });

  function added(record, job) {
    store.update(() => {
      Object.assign(record, { status: "done", message: "added to the queue" });
    });
    core.select(job.id);
    core.upsertJob(job);
    setTimeout(() => all.dismissUpload(record.id), 4000);
  }

  const send = (job, action, opts) => channel.send(job, action, opts);

  /** The pen prompt, when the first layer plotted needs a pen other than the loaded one;
   * its answer runs `action` again (penPromptAnswer). True when it asked. */
  function askPen(job, action, layers) {
    const need = penNeeded(s, job, layers);
    if (need) {
      store.update((st) => {
        st.penPrompt = { jobId: job.id, action, ...need };
      });
    }
    return Boolean(need);
  }

  return {
    onJobActionAnswer: (msg) => channel.answered(msg),
    onJobSocketDown: () => channel.down(),

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
      uploadJob(form, progress).then((job) => added(record, job), (err) => store.update(() => {
        Object.assign(record, { status: "failed", message: uploadMessage(err), errors: uploadErrors(err) });
      }));
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
        added(record, await uploadJob(form, () => {}));
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
      core.select(job.id);
      store.update((st) => {
        st.placementError = "";
      });
    },

    placementChanged(patch) {
      store.update((st) => {
        st.placement = { ...st.placement, ...patch }; // only the fields edited
        st.placementDirty = true;
      });
      clearTimeout(placementTimer);
      placementTimer = setTimeout(all.applyPlacement, 300);
    },

    /** The offset that puts the drawing's lower-left corner where the pen is now. */
    placeHere() {
      const job = previewJob(s);
      const m = s.machine;
      if (!job || !job.bounds || !m || !m.position) return;
      const p = s.placement;
      const round = (v) => Math.round(v * 100) / 100;
      all.placementChanged({
        dx: round(p.dx + m.position.x - job.bounds.min_x), dy: round(p.dy + m.position.y - job.bounds.min_y),
      });
    },

    /** Re-import the shown job with the form's placement (when its actions allow an edit),
     * then reload its preview. A refused change puts back what the job really has. */
    async applyPlacement() {
      const job = previewJob(s);
      if (!job || !can(job, "edit")) return;
      const sent = s.placement;
      try {
        const updated = await api.patch(`/api/jobs/${encodeURIComponent(job.id)}`, {
          placement: placementFields(sent),
        });
        store.update((st) => {
          st.placementError = "";
          if (st.placement === sent) st.placementDirty = false; // not edited meanwhile
        });
        if (updated && updated.id !== undefined) core.upsertJob(updated);
        else await core.loadJobs();
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

    /** Tick or untick a layer, or choose the one to start at, for the job's next start. */
    chooseLayers(id, patch) {
      const job = s.jobs.find((j) => sameId(j.id, id));
      if (!job) return;
      store.update((st) => {
        const { tickedChange, ...rest } = patch;
        const choice = { ...layerChoice(st, job), ...rest };
        if (tickedChange) {
          const [n, on] = tickedChange;
          choice.ticked = on ? [...choice.ticked, n] : choice.ticked.filter((k) => k !== n);
        }
        choice.ticked = [...new Set(choice.ticked)].sort((a, b) => a - b);
        st.layerChoice = { ...st.layerChoice, [job.id]: choice };
      });
    },

    /** One of a job's actions (a button of its row or card), or up/down in the queue. */
    async jobAction(id, action, confirmedPen = false) {
      const job = s.jobs.find((j) => sameId(j.id, id));
      if (!job) return;
      if (action === "stop") {
        estop.trigger({ plotter: job.plotter || job.target || s.plotter });
        return;
      }
      if (action === "resume_from") {
        core.select(job.id);
        store.update((st) => {
          st.tab = "plot";
          st.notice = { text: `Click the drawing where “${job.name}” should start again.`, error: false };
        });
        document.getElementById("preview")?.scrollIntoView({ block: "nearest" });
        return;
      }
      const opts = { layers: layerChoice(s, job) };
      if (action === "resume" || action === "home_then_resume") {
        const chosen = resumeChoice(job, opts.layers);
        if (chosen.error) {
          core.notice(`resume “${job.name}”: ${chosen.error}`);
          return;
        }
        const fromLayer = chosen.action === "resume_from";
        // from a layer's start, as at Start: that layer's pen is asked for first
        if (fromLayer && !confirmedPen && askPen(job, action, opts.layers)) return;
        // as a plain resume does, a resume from a layer homes a plotter in Alarm first
        const board = s.plotters[job.plotter] || s.machine;
        const home = action === "home_then_resume" || Boolean(board && board.state === "Alarm");
        opts.body = fromLayer && home ? { ...chosen.body, home: true } : chosen.body;
        if (fromLayer) action = "resume_from";
      }
      if (action === "up" || action === "down") {
        const movable = s.jobs.filter((j) => can(j, "move"));
        opts.position = movable.indexOf(job) + (action === "up" ? -1 : 1);
        action = "move";
      }
      if ((action === "start" || action === "restart") && !confirmedPen && askPen(job, action, opts.layers)) {
        return;
      }
      if (["start", "restart", "resume", "resume_from"].includes(action)) askPermission();
      try {
        const updated = await send(job, action, opts);
        if (action === "delete") {
          store.update((st) => {
            st.jobs = st.jobs.filter((j) => !sameId(j.id, job.id));
            delete st.previews[job.id];
          });
          return;
        }
        if (action === "move") await core.loadJobs();
        else if (updated && updated.id !== undefined) core.upsertJob(updated);
        if (["start", "restart", "resume", "resume_from"].includes(action)) {
          core.select(job.id);
          store.update((st) => {
            st.estop = null;
            const { [job.id]: _used, ...others } = st.layerChoice; // the next stop starts afresh
            st.layerChoice = others;
          });
        }
      } catch (err) {
        core.notice(`${action.replaceAll("_", " ")} “${job.name}”: ${err.message}`);
      }
    },

    /** The pen prompt's answer: the pen is loaded (start), or not now. */
    penPromptAnswer(loaded) {
      const p = s.penPrompt;
      store.update((st) => {
        st.penPrompt = null;
        if (loaded && p) st.loadedPens = { ...st.loadedPens, [p.plotter || ""]: p.pen };
      });
      if (loaded && p) all.jobAction(p.jobId, p.action, true);
    },

    /** A click on the preview: the nearest point on any stroke of a job that can resume
     * from a point (within a few pixels), with its layer and distance along the stroke. */
    pickAt(p) {
      const job = previewJob(s);
      if (!job || !can(job, "resume_from")) return;
      const entry = s.previews[job.id];
      const found = entry && entry.geom ? nearestOnStroke(entry.geom, p.x, p.y, p.tolerance) : null;
      if (!found) return;
      const layer = layerOfLine(job.layers, found.line);
      store.update((st) => {
        st.resumePick = { jobId: job.id, ...found, layer };
      });
    },

    setResumeOverlap(value) {
      const mm = Number(value);
      store.update((st) => {
        st.resumeOverlap = Number.isFinite(mm) && mm >= 0 ? mm : 0;
      });
    },

    /** Resume from the picked point (with the overlap), else where it stopped; `home`:
     * home first. */
    async resumeFromPoint(id, home) {
      const job = s.jobs.find((j) => sameId(j.id, id));
      if (!job) return;
      const pick = s.resumePick && sameId(s.resumePick.jobId, id) ? s.resumePick : null;
      if (!pick) {
        all.jobAction(job.id, home ? "home_then_resume" : "resume");
        return;
      }
      try {
        const updated = await send(job, "resume_from", { pick, overlap: s.resumeOverlap, home, layers: layerChoice(s, job) });
        if (updated && updated.id !== undefined) core.upsertJob(updated);
        store.update((st) => {
          st.resumePick = null;
          st.selectedJobId = job.id;
          st.estop = null;
        });
      } catch (err) {
        core.notice(`resume “${job.name}”: ${err.message}`);
      }
    },

    setHistorySort(key) {
      store.update((st) => {
        st.history = { sort: key, desc: st.history.sort === key ? !st.history.desc : key !== "name" };
      });
    },

    /** Delete every finished job the server lets go (its actions include delete and it
     * cannot be resumed, restarted only). */
    async clearFinished(ids) {
      for (const id of ids) {
        try {
          await send({ id }, "delete");
        } catch (err) {
          core.notice(`delete: ${err.message}`);
        }
      }
      await core.loadJobs();
    },
  };
}
