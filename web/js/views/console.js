// The serial console: the last lines of the log and a line for raw commands.

import { $, el, setText, syncList } from "../dom.js";

export const LOG_LIMIT = 500;

export function bindConsole(actions) {
  const input = $("#command-line");
  const history = [];
  let back = 0;
  $("#command-form").addEventListener("submit", (e) => {
    e.preventDefault();
    const line = input.value.trim();
    if (!line) return;
    history.push(line);
    back = 0;
    input.value = "";
    actions.sendCommand(line);
  });
  input.addEventListener("keydown", (e) => {
    if (e.key !== "ArrowUp" && e.key !== "ArrowDown") return;
    back = Math.max(0, Math.min(history.length, back + (e.key === "ArrowUp" ? 1 : -1)));
    input.value = back ? history[history.length - back] : "";
    e.preventDefault();
  });
}

export function renderConsole(state) {
  const log = $("#log");
  const atBottom = log.scrollTop + log.clientHeight >= log.scrollHeight - 8;
  syncList(log, state.log, (l) => l.seq,
    () => el("li"),
    (li, l) => {
      li.className = l.direction;
      setText(li, `${l.direction === "tx" ? "› " : l.direction === "rx" ? "‹ " : "· "}${l.line}`);
    });
  if (atBottom) log.scrollTop = log.scrollHeight;
  setText($("#command-error"), state.commandError || "");
}
