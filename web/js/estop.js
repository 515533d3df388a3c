// The emergency stop: WebSocket first (fastest path), REST as a fallback when the
// socket is not open or has not acknowledged within ACK_TIMEOUT_MS. Duplicate stops
// are harmless, so when in doubt both paths are used.

import { api } from "./api.js";
import { MOVING_STATES, jobActive } from "./store.js";

const ACK_TIMEOUT_MS = 300;

export function createEstop({ socket, store }) {
  function acknowledge(record, via) {
    if (store.state.estop !== record || record.acked) return;
    record.acked = true;
    record.ackVia = via;
    record.phase = "sent";
    store.update();
  }

  function viaRest(record) {
    record.rest = true;
    api
      .post(store.state.plotterOrder.length > 1 ? "/api/estop" : "/api/machine/estop", {},
        { "X-Plotbridge-Page": store.state.pageId })
      .then(() => acknowledge(record, "rest"))
      .catch((err) => {
        if (store.state.estop !== record || record.acked) return;
        record.phase = "failed";
        record.error = err.message;
        store.update();
      });
  }

  return {
    trigger() {
      // Send before touching anything else on the page.
      // With several plotters the big STOP stops them all (each card has its own).
      const all = store.state.plotterOrder.length > 1;
      const page = store.state.pageId; // the other pages say it came from elsewhere
      const sentOnSocket = socket.send(all ? { type: "estop", all: true, page } : { type: "estop", page });
      const state = store.state;
      const machine = state.machine;
      const record = {
        phase: "sending",
        at: performance.now(),
        acked: false,
        seqAtClick: machine ? machine.seq : 0,
        wasMoving: jobActive(state) || Boolean(machine && MOVING_STATES.has(machine.state)),
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
