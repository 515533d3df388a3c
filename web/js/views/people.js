// Roles in the page (plotbridge/access.py has the rules; the server refuses the rest anyway):
// hides what this person's role cannot do, shows operators the uploads awaiting approval,
// and admins the people, the API keys, the approval setting and the audit log.
// Started by one import in main.js; it waits for the app view and asks GET /api/me.
import { api } from "../api.js";
import { $, el, setText } from "../dom.js";

const RANK = { viewer: 1, submitter: 2, operator: 3, admin: 4 };
const ROLES = Object.keys(RANK);
// the least role each part of the page needs
const NEEDS = [
  ['section[aria-labelledby="add-title"]', "submitter"],
  ['.tab[data-tab="control"]', "operator"],
  ['.tab[data-tab="pens"]', "operator"],
  ['.tab[data-tab="settings"]', "operator"],
  ['.tab[data-tab="console"]', "admin"],
  ["#hold", "operator"],
];
const POLL_MS = 2000;

let me = null;

function may(role) {
  return me && RANK[me.role] >= RANK[role];
}

function applyRole() {
  document.body.dataset.role = me.role;
  for (const [selector, role] of NEEDS) {
    for (const node of document.querySelectorAll(selector)) {
      if (may(role)) node.style.removeProperty("display");
      else node.style.setProperty("display", "none", "important");
    }
  }
  const bar = document.querySelector(".tab")?.parentElement;
  if (bar && !$("#who-am-i")) {
    const plain = "color: inherit; background: transparent; margin-left: auto";
    bar.append(el("span", { id: "who-am-i", style: plain }),
      el("button", { type: "button", id: "logout-everywhere", className: "small", style: plain,
        onclick: async () => {
          await api.post("/api/logout/everywhere");
          location.replace("/");
        } }, "Log out everywhere"));
  }
  setText($("#who-am-i"), `${me.name} (${me.role})`);
}

// ---- approvals (operators) ---------------------------------------------------------

function approvalsCard() {
  let card = $("#approvals");
  if (!card) {
    card = el("section", { id: "approvals", className: "card", "aria-labelledby": "approvals-title" },
      el("h2", { id: "approvals-title" }, "Awaiting approval"),
      el("ul", { id: "approval-list", className: "uploads" }),
      el("p", { id: "approval-error", className: "error", role: "alert" }));
    const add = $('section[aria-labelledby="add-title"]');
    if (add) add.before(card);
    else $("#tab-plot").prepend(card);
  }
  return card;
}

async function refreshApprovals() {
  const card = approvalsCard();
  const waiting = (await api.get("/api/jobs")).filter((job) => job.state === "awaiting_approval");
  card.hidden = waiting.length === 0;
  const list = $("#approval-list");
  list.replaceChildren(...waiting.map((job) => el("li", { className: "row wrap", "data-job": job.id },
    el("strong", { className: "grow" }, job.name),
    el("span", { className: "hint" }, `from ${job.owner ?? "?"}`
      + (job.approval && job.approval.start ? ", to start" : "")),
    el("button", { type: "button", className: "primary small", onclick: () => decide(job, "approve") },
      "Approve"),
    el("button", { type: "button", className: "small", onclick: () => decide(job, "decline") },
      "Decline"))));
}

async function decide(job, action) {
  let body = {};
  if (action === "decline") {
    const reason = window.prompt(`Why is “${job.name}” declined? Its sender sees this.`);
    if (!reason) return;
    body = { reason };
  }
  try {
    await api.post(`/api/jobs/${encodeURIComponent(job.id)}/${action}`, body);
    setText($("#approval-error"), "");
  } catch (err) {
    setText($("#approval-error"), err.message);
  }
  await refreshApprovals();
}

// ---- people, keys, the approval setting, the audit log (admins) ----------------------

function roleSelect(id) {
  return el("select", { id }, ...ROLES.map((r) => el("option", { value: r }, r)));
}

function adminCard() {
  let card = $("#people");
  if (card) return card;
  const shown = el("p", { id: "people-shown", className: "mono", role: "status" });
  const add = (kind) => el("form", {
    className: "row wrap", id: `${kind}-add`,
    onsubmit: async (e) => {
      e.preventDefault();
      const name = $(`#${kind}-name`).value.trim();
      try {
        const made = await api.post(`/api/${kind}`, { name, role: $(`#${kind}-role`).value });
        setText(shown, kind === "keys"
          ? `Key for ${made.name} (shown only now): ${made.key}`
          : `One-time login link for ${made.name}: ${made.link}`);
        $(`#${kind}-name`).value = "";
      } catch (err) {
        setText(shown, err.message);
      }
      await refreshAdmin();
    },
  }, el("input", { id: `${kind}-name`, required: true, placeholder: kind === "keys" ? "key name" : "name" }),
  roleSelect(`${kind}-role`),
  el("button", { type: "submit", className: "small" }, kind === "keys" ? "Add key" : "Add person"));
  card = el("section", { id: "people", className: "card", "aria-labelledby": "people-title" },
    el("h2", { id: "people-title" }, "People and keys"),
    el("label", {}, "Uploads that wait for approval ",
      el("select", {
        id: "approval-mode",
        onchange: (e) => api.put("/api/settings/approval", { mode: e.target.value }),
      }, ...["submitters", "all", "none"].map((m) => el("option", { value: m }, m)))),
    el("h3", {}, "People"), el("ul", { id: "people-list", className: "uploads" }), add("people"),
    el("h3", {}, "API keys"), el("ul", { id: "keys-list", className: "uploads" }), add("keys"),
    shown,
    el("h3", {}, "Audit log"),
    el("a", { href: "/api/audit/export", download: "plotbridge-audit.jsonl" }, "Export (JSON lines)"),
    el("ul", { id: "audit-list", className: "uploads mono" }));
  $("#tab-settings").append(card);
  return card;
}

function row(name, role, buttons) {
  return el("li", { className: "row wrap", "data-name": name },
    el("strong", { className: "grow" }, name), el("span", { className: "hint" }, role), ...buttons);
}

async function refreshAdmin() {
  adminCard();
  const [people, keys, log, approval] = await Promise.all([api.get("/api/people"),
    api.get("/api/keys"), api.get("/api/audit?limit=20"), api.get("/api/settings/approval")]);
  $("#approval-mode").value = approval.mode;
  const shown = $("#people-shown");
  $("#people-list").replaceChildren(...people.map((p) => row(p.name, p.role, [
    el("button", { type: "button", className: "small", onclick: async () => {
      const made = await api.post(`/api/people/${encodeURIComponent(p.name)}/reset`);
      setText(shown, `New one-time login link for ${p.name}: ${made.link}`);
    } }, "New link"),
    el("button", { type: "button", className: "small", onclick: async () => {
      await api.del(`/api/people/${encodeURIComponent(p.name)}`);
      await refreshAdmin();
    } }, "Remove")])));
  $("#keys-list").replaceChildren(...keys.map((k) => row(k.name, k.role, [
    el("button", { type: "button", className: "small", onclick: async () => {
      await api.del(`/api/keys/${encodeURIComponent(k.name)}`);
      await refreshAdmin();
    } }, "Remove")])));
  $("#audit-list").replaceChildren(...log.map((e) => el("li", {},
    `${new Date(e.at * 1000).toLocaleTimeString()} ${e.who}: ${e.action}${e.target ? ` ${e.target}` : ""}`
    + (e.detail && e.detail.refused ? ` (refused ${e.detail.refused})` : ""))));
}

// ---- start ------------------------------------------------------------------------------

async function poll() {
  const app = $("#app");
  if (!app || app.hidden) {
    me = null;
    return;
  }
  try {
    if (!me) {
      me = await api.get("/api/me");
      applyRole();
    }
    if (may("operator")) await refreshApprovals();
    if (may("admin") && !$("#tab-settings").hidden) await refreshAdmin();
  } catch {
    me = null; // logged out or unreachable: the page's own handlers tell
  }
}

setInterval(poll, POLL_MS);
poll();
