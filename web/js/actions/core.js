// What every group of actions shares: applying messages through the reducer, the selected
// plotter's paths, loading jobs and previews, calling a machine verb.

import { api } from "../api.js";
import { notifyJob } from "../notify.js";
import { buildGeometry } from "../preview-data.js";
import { reduce, withPlacement } from "../reducer.js";
import { previewJob } from "../store.js";

export const SELECTED_KEY = "plotbridge.selectedJob"; // this tab's selected job (sessionStorage)
export const asList = (data, key) => (Array.isArray(data) ? data : (data && data[key]) || []);
export const sameId = (a, b) => String(a) === String(b);

/** A preview's version: re-fetch when a re-import changed the job. */
const previewVersion = (job) => JSON.stringify([job.lines_total, job.bounds, job.placement]);

export function createCore(store) {
  const s = store.state;

  // Socket messages heard so far, by kind. A REST answer that crossed a socket message of
  // its kind on the way is dropped: the socket delivers every change, and the older answer
  // applied last would show a stale state until the next change (an idle board may not
  // change for hours).
  const heard = { machine: 0, jobs: 0 };
  const unchanged = (kind) => {
    const at = heard[kind];
    return () => heard[kind] === at;
  };

  /** Apply an incoming message (or a REST answer shaped as one) through the reducer. */
  function apply(msg) {
    store.update((st) => {
      Object.assign(st, reduce(st, msg));
    });
  }

  /** A board verb's path: the selected plotter's (or `name`'s) when there are several. */
  function machinePath(verb = "", name = s.plotter) {
    const several = s.plotterOrder.length > 1 && name;
    const base = several ? `/api/plotters/${encodeURIComponent(name)}/machine` : "/api/machine";
    return verb ? `${base}/${verb}` : base;
  }

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
    ensurePreview();
  }

  const notice = (text, error = true) => store.update((st) => {
    st.notice = { text, error };
  });

  async function machineCall(path, body) {
    store.update((st) => {
      st.controlError = "";
    });
    try {
      await api.post(path, body);
      return true;
    } catch (err) {
      if (err.status !== 401) {
        store.update((st) => {
          st.controlError = err.message;
        });
        notice(err.message);
      }
      return false;
    }
  }

  return { heard, unchanged, apply, machinePath, ensurePreview, upsertJob, loadJobs, select, notice, machineCall };
}
