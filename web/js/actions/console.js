// The console: the serial log and typed commands.

import { api } from "../api.js";
import { LOG_LIMIT } from "../views/console.js";
import { errorText } from "../words.js";
import { asList } from "./core.js";

export function consoleActions({ store, socket, core, all }) {
  const s = store.state;
  return {
    appendLog(lines) {
      store.update((st) => {
        for (const entry of lines) {
          if (!entry || typeof entry !== "object") continue;
          const direction = entry.direction === "tx" ? "tx" : "rx";
          st.log.push({ seq: ++st.logSeq, direction, line: String(entry.line ?? "") });
        }
        if (st.log.length > LOG_LIMIT) st.log.splice(0, st.log.length - LOG_LIMIT);
      });
    },

    async sendCommand(line, confirm = false) {
      store.update((st) => {
        st.commandError = "";
      });
      if (socket.send({ type: "command", line, plotter: s.plotter, confirm })) return; // the log shows tx and the answer
      all.appendLog([{ direction: "tx", line }]);
      try {
        const data = await api.post(core.machinePath("command"), { line, confirm });
        all.appendLog(asList(data, "responses").map((r) => ({ direction: "rx", line: r })));
      } catch (err) {
        if (err.status === 401) return;
        if (err.status === 428 && !confirm) {
          all.confirmCommand(line, err.message);
          return;
        }
        store.update((st) => {
          st.commandError = errorText(err.message);
        });
      }
    },

    // A line that wedges or wipes the board ($SLP, $RST=): the server said what it does.
    confirmCommand(line, what) {
      if (window.confirm(`${what}\n\nSend ${line}?`)) all.sendCommand(line, true);
      else store.update((st) => { st.commandError = `${line} not sent`; });
    },
  };
}
