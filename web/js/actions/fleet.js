// The MQTT fleet: its view comes as "fleet" messages on the socket (the server sends it
// when it changes); read once over REST when the tab opens without one, and while the
// socket is down. STOPs of other bridges' plotters go through this bridge's broker.

import { api } from "../api.js";

export function fleetActions({ store, core }) {
  const s = store.state;
  const failed = (text) => store.update((st) => {
    st.fleetError = text;
  });
  return {
    async refreshFleet() {
      try {
        core.apply({ type: "fleet", fleet: await api.get("/api/fleet") });
        if (!s.fleetError.startsWith("STOP")) failed("");
      } catch (err) {
        failed(err.message);
      }
    },

    async fleetStop(path, body) {
      try {
        await api.post(path, body);
        failed("");
      } catch (err) {
        failed(`STOP: ${err.message}`);
      }
    },
  };
}
