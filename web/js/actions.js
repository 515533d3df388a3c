// Everything the page does to the server, one module per concern (actions/). Each action
// updates the one state object; the views render from it.

import { consoleActions } from "./actions/console.js";
import { SELECTED_KEY, createCore } from "./actions/core.js";
import { fleetActions } from "./actions/fleet.js";
import { jobActions } from "./actions/jobs.js";
import { machineActions } from "./actions/machine.js";
import { sessionActions } from "./actions/session.js";
import { settingsActions } from "./actions/settings.js";
import { createPenActions, loadPens } from "./views/pens.js";

export { layerChoice, placementFields, uploadErrors } from "./actions/jobs.js";

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
  store.state.pageId = newPageId();
  store.state.selectedJobId = storedSelection();
  const all = {};
  const ctx = { store, socket, estop, core: createCore(store), all };
  Object.assign(all,
    sessionActions(ctx), jobActions(ctx), machineActions(ctx), settingsActions(ctx), consoleActions(ctx),
    fleetActions(ctx),
    { loadPens: () => loadPens(store), pens: createPenActions(store) });
  return all;
}
