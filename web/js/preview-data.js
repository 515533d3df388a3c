// Pure geometry for the preview: flattening the server's /preview body into typed
// arrays, mapping job progress onto points, paper rectangles. No DOM here.

/** Points per cached Path2D chunk: the partially drawn chunk is rebuilt per frame. */
export const CHUNK = 4096;

const PAPER_MM = {
  A6: [105, 148],
  A5: [148, 210],
  A4: [210, 297],
  A3: [297, 420],
  letter: [215.9, 279.4],
};

function polylines(list) {
  return Array.isArray(list) ? list.filter((p) => Array.isArray(p) && p.length > 0) : [];
}

/** Flatten polylines [[[x, y], ...], ...] into {coords: Float32Array, starts: Uint32Array}. */
function flatten(list) {
  const lines = polylines(list);
  let total = 0;
  for (const line of lines) total += line.length;
  const coords = new Float32Array(total * 2);
  const starts = new Uint32Array(lines.length + 1);
  let i = 0;
  lines.forEach((line, n) => {
    starts[n] = i / 2;
    for (const pt of line) {
      coords[i++] = pt[0];
      coords[i++] = pt[1];
    }
  });
  starts[lines.length] = total;
  return { coords, starts, count: total };
}

/**
 * The program lines [pen-down, pen-up] of each stroke, from the preview's `lines`
 * (the importer writes them), or null for a preview without them or that does not match.
 */
function strokeLines(preview, nStrokes) {
  const spans = preview && preview.lines;
  if (!Array.isArray(spans) || spans.length !== nStrokes) return null;
  const first = new Float64Array(nStrokes);
  const last = new Float64Array(nStrokes);
  for (let s = 0; s < nStrokes; s++) {
    const span = spans[s];
    if (!Array.isArray(span) || !(span[1] >= span[0])) return null;
    first[s] = span[0];
    last[s] = span[1];
  }
  return { first, last };
}

/**
 * Runs of consecutive strokes of one colour: [{from, to (point indices), colour}];
 * colour null where the preview names none.
 */
function colourRuns(preview, strokes) {
  const colours = Array.isArray(preview && preview.colours) ? preview.colours : [];
  const runs = [];
  const nStrokes = strokes.starts.length - 1;
  for (let s = 0; s < nStrokes; s++) {
    const c = typeof colours[s] === "string" ? colours[s] : null;
    const last = runs[runs.length - 1];
    if (last && last.colour === c) last.to = strokes.starts[s + 1];
    else runs.push({ from: strokes.starts[s], to: strokes.starts[s + 1], colour: c });
  }
  return runs;
}

/** Geometry for drawing: strokes, travel, bounds, colours and the program line map. */
export function buildGeometry(preview) {
  const strokes = flatten(preview && preview.strokes);
  const travel = flatten(preview && preview.travel);
  // Without the importer's line spans: the normalized program (docs/INTERNALS.md) spends
  // G0 + M3 + (n-1) G1 + M5 on an n-point stroke after a 3-line header.
  const nStrokes = strokes.starts.length - 1;
  const lineEnd = new Float64Array(nStrokes);
  let line = 3;
  for (let s = 0; s < nStrokes; s++) {
    line += strokes.starts[s + 1] - strokes.starts[s] + 2;
    lineEnd[s] = line;
  }
  return {
    strokes, travel, lineEnd, expectedLines: line + 1, bounds: boundsOf(strokes),
    lines: strokeLines(preview, nStrokes), colours: colourRuns(preview, strokes),
    // outlines of the SVG's filled shapes (drawn as outlines or hatched): shown tinted
    fills: polylines(preview && preview.fills),
  };
}

function boundsOf(...sets) {
  let minX = Infinity, minY = Infinity, maxX = -Infinity, maxY = -Infinity;
  for (const { coords } of sets) {
    for (let i = 0; i < coords.length; i += 2) {
      const x = coords[i], y = coords[i + 1];
      if (x < minX) minX = x;
      if (x > maxX) maxX = x;
      if (y < minY) minY = y;
      if (y > maxY) maxY = y;
    }
  }
  return Number.isFinite(minX) ? { minX, minY, maxX, maxY } : null;
}

/** The first stroke whose value in `ends` (ascending) is above `line`. */
function strokeAfter(ends, line) {
  let lo = 0, hi = ends.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (ends[mid] <= line) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/**
 * How many stroke points are drawn after `linesDone` of `linesTotal` program lines:
 * exact at every stroke's ends with the importer's line spans (whatever lines come
 * between strokes, such as the M0 between layers), proportional inside a stroke;
 * without them, laid out as the normalized dialect, proportional otherwise.
 * Returns a global point index: every point below it has been reached.
 */
export function pointsDone(geom, linesDone, linesTotal) {
  const { strokes, lineEnd, expectedLines, lines } = geom;
  const nStrokes = lineEnd.length;
  if (!nStrokes || !linesTotal || linesDone <= 0) return 0;
  if (linesDone >= linesTotal) return strokes.count;
  if (lines) {
    const s = strokeAfter(lines.last, linesDone);
    if (s >= nStrokes) return strokes.count;
    const n = strokes.starts[s + 1] - strokes.starts[s];
    if (linesDone < lines.first[s]) return strokes.starts[s];
    // The pen-down line reaches point 0; the G1/G2/G3 lines after it share the rest.
    const moves = Math.max(1, lines.last[s] - lines.first[s] - 1);
    const reached = Math.floor(((linesDone - lines.first[s]) / moves) * (n - 1));
    return strokes.starts[s] + 1 + Math.min(n - 1, reached);
  }
  const line = linesDone * (expectedLines / linesTotal);
  const lo = strokeAfter(lineEnd, line);
  if (lo >= nStrokes) return strokes.count;
  const strokeFirstLine = lo === 0 ? 3 : lineEnd[lo - 1];
  const n = strokes.starts[lo + 1] - strokes.starts[lo];
  // G0 reaches point 0 (pen up), M3 lowers the pen, the k-th G1 reaches point k.
  const reached = Math.floor(line - strokeFirstLine) - 2;
  return strokes.starts[lo] + Math.max(0, Math.min(n - 1, reached)) + (reached >= 0 ? 1 : 0);
}

/**
 * Acknowledged lines run ahead of the pen by the planner's buffer, and the preview is
 * simplified, so the line estimate is approximate: find the stroke segment the live pen
 * is on, nearest in order to the estimate, within `window` points either side.
 * Returns the points reached (the pen is on the segment ending at that index), or null
 * when the pen is on no segment nearby.
 */
export function refineWithPen(geom, estimate, pen, window = 2000, tolerance = 0.5) {
  if (!pen || !Number.isFinite(pen.x) || !Number.isFinite(pen.y)) return null;
  const { coords, starts, count } = geom.strokes;
  if (count < 2) return null;
  const onSegment = (i) => {
    // segment from point i-1 to point i, only inside one stroke
    const ax = coords[2 * i - 2], ay = coords[2 * i - 1];
    const bx = coords[2 * i], by = coords[2 * i + 1];
    const vx = bx - ax, vy = by - ay;
    const len2 = vx * vx + vy * vy;
    const t = len2 > 0 ? Math.max(0, Math.min(1, ((pen.x - ax) * vx + (pen.y - ay) * vy) / len2)) : 0;
    const dx = ax + t * vx - pen.x, dy = ay + t * vy - pen.y;
    return dx * dx + dy * dy <= tolerance * tolerance;
  };
  const isStart = (i) => {
    // binary search: is i the first point of a stroke (no segment ends there)?
    let lo = 0, hi = starts.length - 1;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (starts[mid] < i) lo = mid + 1;
      else hi = mid;
    }
    return starts[lo] === i;
  };
  const center = Math.max(1, Math.min(count - 1, estimate));
  for (let d = 0; d <= window; d++) {
    for (const i of d ? [center - d, center + d] : [center]) {
      if (i >= 1 && i < count && !isStart(i) && onSegment(i)) return i;
    }
  }
  return null;
}

/** The paper rectangle in machine mm for a job's placement, or null without paper. */
export function paperRect(placement) {
  if (!placement || !placement.paper) return null;
  let name = String(placement.paper);
  let landscape = Boolean(placement.landscape);
  if (name.endsWith("-landscape")) {
    name = name.slice(0, -"-landscape".length);
    landscape = true;
  }
  const size = PAPER_MM[name] ?? PAPER_MM[name.toUpperCase()];
  if (!size) return null;
  const [w, h] = landscape ? [size[1], size[0]] : size;
  return { x: 0, y: 0, w, h };
}

/**
 * The point of any stroke nearest to (x, y) mm, on a segment (not only at vertices), within
 * `tolerance` mm: {x, y, stroke (index), along (mm from the stroke's start), length (the
 * stroke's mm), line (the stroke's first program line, when the preview has them)}, or null.
 */
export function nearestOnStroke(geom, x, y, tolerance = Infinity) {
  const strokes = geom && geom.strokes;
  if (!strokes || strokes.count < 1) return null;
  const { coords, starts } = strokes;
  let best = null, bestD = tolerance * tolerance;
  for (let s = 0; s + 1 < starts.length; s++) {
    const from = starts[s], to = starts[s + 1];
    let run = 0;
    for (let i = from; i < to; i++) {
      const ax = coords[2 * i], ay = coords[2 * i + 1];
      const bx = i + 1 < to ? coords[2 * i + 2] : ax, by = i + 1 < to ? coords[2 * i + 3] : ay;
      const vx = bx - ax, vy = by - ay;
      const len2 = vx * vx + vy * vy;
      const t = len2 > 0 ? Math.max(0, Math.min(1, ((x - ax) * vx + (y - ay) * vy) / len2)) : 0;
      const px = ax + t * vx, py = ay + t * vy;
      const d = (px - x) ** 2 + (py - y) ** 2;
      if (d < bestD || (best === null && d <= bestD)) {
        bestD = d;
        best = { x: px, y: py, stroke: s, along: run + t * Math.sqrt(len2) };
      }
      run += Math.sqrt(len2);
    }
    if (best && best.stroke === s) best.length = run;
  }
  if (best && geom.lines) best.line = geom.lines.first[best.stroke];
  return best;
}

/** The 1-based layer of `layers` (a job's) that program line `line` lies in, or 0. */
export function layerOfLine(layers, line) {
  if (!Array.isArray(layers) || !Number.isFinite(line)) return 0;
  const i = layers.findIndex((l) => line >= l.first_line && line <= l.last_line);
  return i + 1;
}

/** The stroke vertex nearest to (x, y) mm, as {x, y}, or null when nothing is drawn. */
export function nearestVertex(geom, x, y) {
  const coords = geom && geom.strokes ? geom.strokes.coords : null;
  if (!coords || coords.length < 2) return null;
  let best = -1, bestD = Infinity;
  for (let i = 0; i < coords.length; i += 2) {
    const d = (coords[i] - x) ** 2 + (coords[i + 1] - y) ** 2;
    if (d < bestD) {
      bestD = d;
      best = i;
    }
  }
  return { x: coords[best], y: coords[best + 1] };
}
