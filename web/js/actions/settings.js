// The board's $ settings (edit, "try it", save) and the server's webhooks.

import { api } from "../api.js";
import { asList } from "./core.js";

export function settingsActions({ store, core }) {
  const s = store.state;
  const busy = (on) => store.update((st) => {
    st.settings.busy = on;
  });

  const hooks = (patch) => store.update((st) => {
    Object.assign(st.webhooks, patch);
  });

  return {
    /** Reads the board's settings; unsaved edits survive unless `discardEdits` (Reload). */
    async loadSettings(discardEdits = false) {
      store.update((st) => {
        st.settings.busy = true;
        st.settings.error = "";
      });
      try {
        const data = await api.get(core.machinePath("settings"));
        store.update((st) => {
          st.settings.list = asList(data, "settings");
          if (discardEdits) st.settings.edits = {};
          st.settings.rowErrors = {};
          st.settings.message = "";
        });
      } catch (err) {
        store.update((st) => {
          st.settings.error = `Could not read the settings: ${err.message}`;
        });
      } finally {
        busy(false);
      }
    },

    editSetting(id, value) {
      store.update((st) => {
        const original = (st.settings.list || []).find((x) => String(x.id) === id);
        if (original && String(original.value) === value) delete st.settings.edits[id];
        else st.settings.edits[id] = value;
        st.settings.message = "";
      });
    },

    showAllSettings(on) {
      store.update((st) => {
        st.settingsAll = on;
      });
    },

    /** "Try it" for a pen position ($60 up, $61 down): the value (as edited) is written
     * (the server checks its range) and the pen moved there, so the servo shows it live. */
    async tryPen(id) {
      const entry = (s.settings.list || []).find((x) => String(x.id) === id);
      const value = Number(id in s.settings.edits ? s.settings.edits[id] : entry && entry.value);
      store.update((st) => {
        st.settings.busy = true;
        st.settings.error = "";
        st.settings.message = "";
      });
      try {
        await api.put(core.machinePath("settings"), { settings: { [id]: value } });
        await api.post(core.machinePath("pen"), { down: id === "61" });
        store.update((st) => {
          if (entry) entry.value = value;
          delete st.settings.edits[id];
          st.settings.message = `Pen moved ${id === "61" ? "down" : "up"} with $${id}=${value} (saved).`;
        });
      } catch (err) {
        store.update((st) => {
          st.settings.error = `Try $${id}: ${err.message}`;
        });
      } finally {
        busy(false);
      }
    },

    async saveSettings() {
      const edits = s.settings.edits;
      const body = {};
      const rowErrors = {};
      for (const [id, value] of Object.entries(edits)) {
        const n = Number(value);
        if (value.trim() === "" || !Number.isFinite(n)) rowErrors[id] = "not a number";
        else body[id] = n;
      }
      if (Object.keys(rowErrors).length) {
        store.update((st) => {
          st.settings.rowErrors = rowErrors;
          st.settings.message = "";
          st.settings.error = `Not a number: ${Object.keys(rowErrors).map((id) => `$${id}`).join(", ")}`;
        });
        return;
      }
      store.update((st) => {
        st.settings.busy = true;
        st.settings.error = "";
        st.settings.message = "";
        st.settings.rowErrors = {};
      });
      try {
        await api.put(core.machinePath("settings"), { settings: body });
        // The board acknowledged every line: show those values.
        store.update((st) => {
          for (const entry of st.settings.list || []) {
            if (String(entry.id) in body) entry.value = body[String(entry.id)];
          }
          st.settings.edits = {};
          st.settings.message = `Saved ${Object.keys(body).length} setting(s) to the board.`;
        });
      } catch (err) {
        store.update((st) => {
          st.settings.error = err.status === 409 ? "Settings cannot be changed while a job runs." : `Save failed: ${err.message}`;
        });
      } finally {
        busy(false);
      }
    },

    async loadWebhooks() {
      try {
        const data = await api.get("/api/settings/webhooks");
        hooks({ data, error: "" });
      } catch (err) {
        hooks({ error: `Could not read the webhooks: ${err.message}` });
      }
    },

    editWebhookDraft(text) {
      hooks({ draft: text, message: "" });
    },

    /** Save the webhook addresses the server's settings hold (one per line, or `urls`). */
    async saveWebhooks(urls) {
      hooks({ busy: true, error: "", message: "" });
      try {
        const data = await api.put("/api/settings/webhooks", { urls });
        hooks({ data, draft: null, message: `Saved ${urls.length} webhook address(es).` });
      } catch (err) {
        hooks({ error: `Webhooks: ${err.message}` });
      } finally {
        hooks({ busy: false });
      }
    },
  };
}
