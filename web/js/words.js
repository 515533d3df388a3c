// Human words for what the server and the board say: job states, machine states, the
// board's error and alarm numbers (GRBL 1.1's numbering, ../shared/grbl/ has the tables;
// tests/browser/test_ui_words.py checks every number there has a text here), action names.
// Pure.

export const JOB_STATES = {
  queued: "in the queue",
  waiting: "waiting for its plotter",
  running: "plotting",
  paused: "on hold",
  pen_change: "waiting for a pen",
  done: "done",
  failed: "failed",
  cancelled: "cancelled",
  stopped: "stopped",
  interrupted: "interrupted",
  awaiting_approval: "waiting for approval",
};

export const MACHINE_STATES = {
  Idle: "ready",
  Run: "moving",
  Hold: "on hold",
  Jog: "jogging",
  Alarm: "alarm",
  Door: "door open",
  Check: "checking G-code",
  Home: "homing",
  Sleep: "asleep",
  Disconnected: "not connected",
  Lost: "connection lost",
};

export const jobStateText = (state) => JOB_STATES[state] || String(state || "").replaceAll("_", " ");
export const machineStateText = (state) => MACHINE_STATES[String(state || "").split(":")[0]] || String(state || "unknown");

/** What each action is called on a button (one name per action, everywhere). */
export const ACTION_LABELS = {
  start: "Start",
  hold: "Hold",
  continue: "Continue",
  stop: "STOP",
  resume: "Resume",
  home_then_resume: "Home, then resume",
  resume_from: "Resume from a point",
  restart: "Plot again from the start",
  cancel: "Cancel",
  frame: "Frame",
  delete: "Delete",
  approve: "Approve",
  decline: "Decline",
};

/** The board's error numbers, in our words (the meaning GRBL 1.1 gives each). */
export const ERRORS = {
  1: "a G-code word has no letter",
  2: "a number is missing or badly written",
  3: "the $ command is not known",
  4: "a value must not be negative",
  5: "homing is switched off in the settings ($22)",
  6: "a step pulse must be at least 3 µs",
  7: "the settings memory could not be read: defaults are used",
  8: "only possible while the plotter is idle",
  9: "locked by an alarm: home or unlock first",
  10: "soft limits need homing switched on",
  11: "the line is too long",
  12: "the step rate would be too high (above 30 kHz)",
  13: "the safety door is open",
  14: "the startup line is too long to store",
  15: "the move would leave the work area",
  16: "the jog command is not valid",
  17: "laser mode needs PWM on the spindle pin",
  20: "the G-code command is not supported",
  21: "two commands of the same group in one line",
  22: "no feed rate was given",
  23: "a command needs a whole number",
  24: "two commands in one line need the same axis words",
  25: "a G-code word appears twice in one line",
  26: "the command needs axis words and has none",
  27: "the line number is out of range",
  28: "the command is missing a value it needs",
  29: "G59.x work offsets are not supported",
  30: "G53 needs G0 or G1 motion",
  31: "axis words the command does not use",
  32: "an arc needs axis words in its plane",
  33: "the motion target is not valid",
  34: "the arc radius does not fit the arc",
  35: "an arc needs offset words in its plane",
  36: "words the line does not use",
  37: "tool length offset is not along the Z axis",
  38: "the tool number is too large",
};

/** The board's alarm numbers, in our words. 10 is this firmware's own: the stop button. */
export const ALARMS = {
  1: "a limit switch was hit: the position is probably lost, home the plotter",
  2: "a move went outside the work area (position kept): unlock to go on",
  3: "reset while moving: the position is probably lost, home the plotter",
  4: "probe failed: not in the expected state before probing",
  5: "probe failed: it did not touch within the travel",
  6: "homing failed: reset during the homing cycle",
  7: "homing failed: the safety door opened while homing",
  8: "homing failed: the switch did not clear on pull-off",
  9: "homing failed: no limit switch was found",
  10: "the emergency-stop button on the plotter was pressed",
};

/** `error:9` or a message holding one, in words: "locked by an alarm ... (error 9)". */
export function errorText(text) {
  const s = String(text ?? "");
  return s.replace(/error:(\d+)/g, (all, n) => (ERRORS[n] ? `${ERRORS[n]} (error ${n})` : all))
    .replace(/ALARM:(\d+)/g, (all, n) => (ALARMS[n] ? `alarm: ${ALARMS[n]} (alarm ${n})` : all));
}
