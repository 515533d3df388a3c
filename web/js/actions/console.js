// The console: the serial log and typed commands.

import { api } from "../api.js";
import { LOG_LIMIT } from "../views/console.js";
import { errorText } from "../words.js";
import { asList } from "./core.js";

export function consoleActions({ store, socket, core, all }) {
  const s = store.state;
  return {
    appendLog(direction, line) {
      store.update((st) => {
        st.log.push({ seq: ++st.logSeq, direction, line: String(line) });
        if (st.log.length > LOG_LIMIT) st.log.splice(0, st.log.length - LOG_LIMIT);
      });
    },

    async sendCommand(line) {
      store.update((st) => {
        st.commandError = "";
      });
      if (socket.send({ type: "command", line, plotter: s.plotter })) return; // the log shows tx and the answer
      all.appendLog("tx", line);
      try {
        const data = await api.post(core.machinePath("command"), { line });
        for (const r of asList(data, "responses")) all.appendLog("rx", r);
      } catch (err) {
        if (err.status === 401) return;
        store.update((st) => {
          st.commandError = errorText(err.message);
        });
      }
    },
  };
}
