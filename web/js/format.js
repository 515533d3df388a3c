// Pure formatting helpers shared by the views.

export function duration(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(seconds)) return "–";
  const s = Math.max(0, Math.round(seconds));
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const sec = s % 60;
  if (h) return `${h} h ${String(m).padStart(2, "0")} min`;
  if (m) return `${m} min ${String(sec).padStart(2, "0")} s`;
  return `${sec} s`;
}

export function mm(value, digits = 2) {
  return Number.isFinite(value) ? value.toFixed(digits) : "–";
}

/** A pen-down length: millimetres below a metre, metres above. */
export function length(millimetres) {
  if (!Number.isFinite(millimetres)) return "–";
  return millimetres < 1000 ? `${Math.round(millimetres)} mm` : `${(millimetres / 1000).toFixed(2)} m`;
}

export function percent(fraction) {
  return Number.isFinite(fraction) ? `${Math.floor(Math.min(1, Math.max(0, fraction)) * 100)} %` : "–";
}

export function bytes(n) {
  if (!Number.isFinite(n)) return "–";
  if (n < 1024) return `${n} B`;
  if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KB`;
  return `${(n / 1024 / 1024).toFixed(1)} MB`;
}

/** GRBL alarm numbers as this firmware uses them (docs/INTERNALS.md). */
export const ALARMS = {
  1: "hard limit: a limit switch was hit",
  2: "soft limit: a target was outside the work area",
  3: "reset while moving: the position is lost",
  6: "homing failed: reset during the homing cycle",
  8: "homing failed: the switch did not clear on pull-off",
  9: "homing failed: no limit switch found",
  10: "the emergency-stop button on the machine was pressed",
};

/** A layer's name as people read it: the server's `label` (a colour code in words), never
 * a code. `number`: 1-based, for a layer without one. */
export const layerTitle = (layer, number) => (layer && (layer.label || layer.name)) || `layer ${number}`;
