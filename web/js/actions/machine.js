// The boards: the selected plotter, hold and continue, stops, home (one or all), unlock,
// pen, motors, jog, and the banners' buttons.

import { can } from "../job-actions.js";
import { holdAction, plotterJob } from "../store.js";

export function machineActions({ store, socket, estop, core, all }) {
  const s = store.state;

  /** Home and unlock clear the stopped state: the panel goes once they succeed. */
  async function clearing(path) {
    if (await core.machineCall(path)) estop.dismiss();
  }

  /** Hold or continue a plotter: its job's action when it has one, else the board's own
   * feed hold (`!`/`~`) by the WebSocket, REST if it is closed. */
  function holdOrContinueOn(name, what) {
    const job = plotterJob(s, name);
    if (job && can(job, what)) return all.jobAction(job.id, what);
    const type = what === "hold" ? "pause" : "resume";
    if (!socket.send({ type, plotter: name })) core.machineCall(core.machinePath(what, name));
    return undefined;
  }

  const stoppedOne = () => (s.estop && s.estop.names && s.estop.names.length === 1 ? s.estop.names[0] : s.plotter);

  return {
    selectPlotter(name) {
      store.update((st) => {
        st.plotter = name;
        if (st.plotters[name]) {
          st.machineSeq += 1;
          st.machine = { ...st.plotters[name], seq: st.machineSeq };
        }
      });
      all.loadSettings();
      core.ensurePreview();
    },
    /** Any STOP: the big one, a card's (`plotter`), STOP ALL (`all`). */
    stop: (opts) => estop.trigger(opts),

    /** The big Hold/Continue button, for the selected plotter. */
    holdOrContinue() {
      const what = holdAction(s);
      if (what) holdOrContinueOn(s.plotter, what);
    },
    /** A plotter card's Hold or Continue. */
    holdPlotter: (name, what) => holdOrContinueOn(name, what),

    home: () => clearing(core.machinePath("home")),
    unlock: () => clearing(core.machinePath("unlock")),
    /** The stop panel's Home and Unlock: the plotter that was stopped. */
    homeStopped: () => clearing(core.machinePath("home", stoppedOne())),
    unlockStopped: () => clearing(core.machinePath("unlock", stoppedOne())),
    /** After STOP ALL: home every plotter at once; the panel goes once all have homed. */
    async homeAll() {
      const names = s.estop && s.estop.names && s.estop.names.length ? s.estop.names : s.plotterOrder;
      const done = await Promise.all(names.map((name) => core.machineCall(core.machinePath("home", name))));
      if (done.every(Boolean)) estop.dismiss();
    },
    pen: (down) => core.machineCall(core.machinePath("pen"), { down }),
    motors: (enabled) => core.machineCall(core.machinePath("motors"), { enabled }),
    jog: (ux, uy) => core.machineCall(core.machinePath("jog"), { dx: ux * s.jog.step, dy: uy * s.jog.step, feed: s.jog.feed }),
    setJog(patch) {
      store.update((st) => {
        Object.assign(st.jog, patch);
      });
    },
    dismissEstop: () => estop.dismiss(),

    bannerAction(action, id) {
      if (action === "reconnect") socket.reconnectNow();
      else if (action === "home") all.home();
      else if (action === "unlock") all.unlock();
      else if (action === "continue-machine") holdOrContinueOn(s.plotter, "continue");
      else if (id) all.jobAction(id, action);
    },
  };
}
