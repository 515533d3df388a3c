// The emergency stop, one path for every STOP on the page (the big one, a plotter card's,
// STOP ALL, a job's): WebSocket first (fastest path), REST as a fallback when the socket
// is not open or has not acknowledged within ACK_TIMEOUT_MS. Duplicate stops are
// harmless, so when in doubt both paths are used. Every stop shows the same panel,
// naming the plotter(s) it stopped.

import { api } from "./api.js";
import { isActive } from "./job-actions.js";
import { MOVING_STATES, seqNow } from "./store.js";

const ACK_TIMEOUT_MS = 300;

/** What a stop addresses: {scope: "all"|"plotter"|"only", names: [...]}. The big STOP
 * stops every plotter when there are several. Pure. */
export function stopScope(state, plotter = null, all = false) {
  const several = state.plotterOrder.length > 1;
  if (all || (!plotter && several)) return { scope: "all", names: [...state.plotterOrder] };
  if (plotter && several) return { scope: "plotter", names: [plotter] };
  return { scope: "only", names: state.plotterOrder.slice(0, 1) };
}

export function createEstop({ socket, store }) {
  function acknowledge(record, via) {
    if (store.state.estop !== record || record.acked) return;
    record.acked = true;
    record.ackVia = via;
    record.phase = "sent";
    store.update();
  }

  function restPath(record) {
    if (record.scope === "all") return "/api/estop";
    if (record.scope === "plotter") return `/api/plotters/${encodeURIComponent(record.names[0])}/machine/estop`;
    return "/api/machine/estop";
  }

  function viaRest(record) {
    record.rest = true;
    api
      .post(restPath(record), {}, { "X-Plotbridge-Page": store.state.pageId })
      .then(() => acknowledge(record, "rest"))
      .catch((err) => {
        if (store.state.estop !== record || record.acked) return;
        record.phase = "failed";
        record.error = err.message;
        store.update();
      });
  }

  return {
    /** Stop: every plotter (`all`, or the big STOP with several), or the one named. */
    trigger({ plotter = null, all = false } = {}) {
      const state = store.state;
      const { scope, names } = stopScope(state, plotter, all);
      const page = state.pageId; // the other pages say it came from elsewhere
      // Send before touching anything else on the page.
      const msg = scope === "all" ? { type: "estop", all: true, page }
        : scope === "plotter" ? { type: "estop", plotter: names[0], page } : { type: "estop", page };
      const sentOnSocket = socket.send(msg);
      const moving = names.some((name) => {
        const m = name === state.plotter || scope === "only" ? state.machine : state.plotters[name];
        return Boolean(m && MOVING_STATES.has(m.state));
      });
      const record = {
        phase: "sending",
        at: performance.now(),
        acked: false,
        scope,
        names: scope === "only" ? [] : names,
        seqAtClick: seqNow(state, scope === "only" ? [] : names),
        wasMoving: moving || state.jobs.some((j) => isActive(j) && (scope !== "plotter" || j.plotter === names[0])),
        error: "",
      };
      state.estop = record;
      if (sentOnSocket) {
        setTimeout(() => {
          if (store.state.estop === record && !record.acked) viaRest(record);
        }, ACK_TIMEOUT_MS);
      } else {
        viaRest(record);
      }
      store.renderNow();
    },
    /** A WebSocket ack for "estop". */
    onSocketAck() {
      const record = store.state.estop;
      if (record) acknowledge(record, "ws");
    },
    dismiss() {
      store.update((s) => {
        s.estop = null;
      });
    },
  };
}
