// Logging in and out, the live connection (WebSocket messages, REST resync and polling
// while it is down), loading everything the page shows.

import { api, ApiError } from "../api.js";
import { errorText } from "../words.js";
import { asList } from "./core.js";

const POLL_MS = 2000; // REST polling while the WebSocket is down

export function sessionActions({ store, socket, estop, core, all }) {
  const s = store.state;
  let pollTimer = null;

  /** A machine report: kept per plotter; the selected one (the first by default) is shown. */
  function onMachine(msg) {
    const wasConnected = Boolean(s.machine && s.machine.connected);
    core.apply(msg);
    // the board's settings (and the work area) are read again when it (re)connects
    if (s.machine && s.machine.connected && !wasConnected && s.view === "app") all.loadSettings();
  }

  /** The selected plotter's machine over REST; `answered` runs on any answer. */
  async function loadMachine(answered = () => {}) {
    const fresh = core.unchanged("machine");
    const m = await api.get(core.machinePath());
    answered();
    if (fresh()) onMachine({ type: "machine", machine: m });
  }

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
    core.loadJobs().catch(() => {});
  }

  return {
    setMachine: (m) => onMachine({ type: "machine", machine: m }),
    upsertJob: core.upsertJob,
    loadJobs: core.loadJobs,

    /** Everything over REST; resolves when the machine's answer has been applied. */
    loadAll() {
      const machine = loadMachine().catch(() => {});
      core.loadJobs().catch(() => {});
      api.get("/api/server").then((d) => store.update((st) => {
        st.server = d;
      })).catch(() => {});
      all.loadPens();
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
          st.loginNotice = "";
        });
        all.enterApp();
      } catch (err) {
        store.update((st) => {
          st.view = "login";
          st.login = { busy: false, error: err.status === 401 ? "Wrong token." : err.message };
        });
      }
    },

    async logout() {
      try {
        await api.post("/api/logout");
      } finally {
        all.leaveApp();
      }
    },

    enterApp() {
      store.update((st) => {
        st.view = "app";
      });
      socket.start();
      all.loadAll();
    },

    leaveApp() {
      socket.stop();
      clearInterval(pollTimer);
      store.update((st) => {
        st.view = "login";
        st.estop = null;
      });
    },

    onSocketMessage(msg) {
      if (msg.type === "machine") core.heard.machine += 1;
      else if (["job", "jobs", "job_deleted", "queue"].includes(msg.type)) core.heard.jobs += 1;
      if (msg.type === "machine") onMachine(msg);
      else if (msg.type === "job") core.upsertJob(msg.job && typeof msg.job === "object" ? msg.job : msg);
      else if (["jobs", "job_deleted", "queue", "stopped", "pens"].includes(msg.type)) {
        core.apply(msg);
        core.ensurePreview();
      } else if (msg.type === "fleet") core.apply(msg);
      else if (msg.type === "log") all.appendLog(Array.isArray(msg.lines) ? msg.lines : []);
      else if (msg.type === "ack" && msg.command === "estop") estop.onSocketAck();
      else if ((msg.type === "ack" || msg.type === "error") && msg.command === "job_action") all.onJobActionAnswer(msg);
      else if (msg.type === "error" && msg.command === "command" && msg.confirm) {
        all.confirmCommand(msg.line, msg.detail);
      } else if (msg.type === "error") {
        store.update((st) => {
          const detail = msg.detail ?? msg.message ?? "error from the server";
          const text = errorText(typeof detail === "string" ? detail : new ApiError(0, detail).message);
          if (msg.command === "command") st.commandError = text;
          else st.notice = { text: `${msg.command ?? "command"}: ${text}`, error: true };
        });
      }
    },

    onSocketStatus(status) {
      if (status.code === 4401) {
        all.leaveApp();
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
      if (!open) all.onJobSocketDown(); // job actions it did not answer go over REST
      if (open !== wasOpen) resync();
      clearInterval(pollTimer);
      pollTimer = open ? null : setInterval(resync, POLL_MS);
    },
  };
}
