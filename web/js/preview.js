// The preview canvas: work area, paper, strokes, pen-up travel, the drawn part and
// the live pen. Redraws happen in requestAnimationFrame, only when something changed.
// Speed for 200,000 points on slow phones:
// - paths are built in device pixels, dropping points closer than MIN_PX to the last one
//   kept and chunks outside the view, and stroked as one-pixel hairlines;
// - the static layer (all but the partially drawn chunk and the pen) lives in an
//   offscreen canvas, rebuilt only when the view, the data or a whole chunk of progress
//   changed, and rebuilt progressively: at most FRAME_BUDGET_MS of chunks per frame into
//   a second canvas, while the last complete one is shown (moved and scaled to the view);
// - while panning or zooming no rebuild starts: the complete layer is moved.

import { CHUNK } from "./preview-data.js";

const COLORS = {
  background: "#e9ecef",
  work: "#f8f9fa",
  workEdge: "#adb5bd",
  paper: "#ffffff",
  paperEdge: "#868e96",
  todo: "#1c3f94",
  done: "#e8590c",
  travel: "rgba(120, 130, 140, 0.35)",
  penDown: "#e03131",
  penUp: "#212529",
  picked: "#2b8a3e",
  filled: "rgba(28, 63, 148, 0.12)",
};
const CLICK_PX = 4; // a press that moves less than this is a click (picks a point), not a pan
const PICK_PX = 10; // a click picks the stroke within this many CSS pixels
const SETTLE_MS = 120; // after the last pan/zoom event, re-render crisp
const FRAME_BUDGET_MS = 8; // static-layer rebuilding per frame
const MIN_PX = 0.6; // device pixels: closer points are not visible apart
// Strokes are one device pixel wide: browsers rasterize such hairlines far faster
// (Chromium's software canvas: 12 ms instead of 330 ms for 200,000 points).
const LINE_PX = 1;

/** Bounding box [minX, minY, maxX, maxY] of each CHUNK points (with the joining point). */
function chunkBoxes(set) {
  const { coords, count } = set;
  const boxes = [];
  for (let first = 0; first < count; first += CHUNK) {
    const last = Math.min(count, first + CHUNK);
    let minX = Infinity, minY = Infinity, maxX = -Infinity, maxY = -Infinity;
    for (let i = Math.max(0, first - 1); i < last; i++) {
      const x = coords[2 * i], y = coords[2 * i + 1];
      if (x < minX) minX = x;
      if (x > maxX) maxX = x;
      if (y < minY) minY = y;
      if (y > maxY) maxY = y;
    }
    boxes.push([minX, minY, maxX, maxY]);
  }
  return boxes;
}

function strokeOf(starts, i) {
  let lo = 0, hi = starts.length - 2;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (starts[mid] <= i) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

/**
 * Append to `path` the segments among points [from, to) in device pixels
 * (x' = a·x + e, y' = f − a·y), keeping only points at least `minPx` from the last kept
 * one (a stroke's last point is always kept). A segment from point from−1 is included
 * when it belongs to the same stroke, so consecutive ranges join up.
 */
function appendPath(path, set, from, to, t, minPx) {
  const { coords, starts } = set;
  if (to <= from) return;
  let stroke = strokeOf(starts, from);
  let i = from > starts[stroke] ? from - 1 : from;
  const min2 = minPx * minPx;
  let lx = t.a * coords[2 * i] + t.e, ly = t.f - t.a * coords[2 * i + 1];
  path.moveTo(lx, ly);
  for (i += 1; i < to; i++) {
    const x = t.a * coords[2 * i] + t.e, y = t.f - t.a * coords[2 * i + 1];
    if (i === starts[stroke + 1]) {
      stroke++;
      path.moveTo(x, y);
      lx = x;
      ly = y;
    } else if ((x - lx) * (x - lx) + (y - ly) * (y - ly) >= min2 || i === starts[stroke + 1] - 1 || i === to - 1) {
      path.lineTo(x, y);
      lx = x;
      ly = y;
    }
  }
}

/** The colour runs of `runs` (buildGeometry's) inside points [from, to). */
function colourRunsIn(runs, from, to) {
  const out = [];
  for (const run of runs) {
    if (run.to <= from || run.from >= to) continue;
    out.push([Math.max(from, run.from), Math.min(to, run.to), run.colour || COLORS.todo]);
  }
  return out.length ? out : [[from, to, COLORS.todo]];
}

/** An offscreen layer; read back every build step, so kept in memory, not on a GPU. */
function layerCanvas() {
  const canvas = document.createElement("canvas");
  canvas.getContext("2d", { willReadFrequently: true });
  return canvas;
}

export class PreviewCanvas {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.front = null; // {canvas, key, view}: the last complete static layer
    this.spare = layerCanvas(); // the next one is built here
    this.build = null; // {key, view, steps, next}: the rebuild in progress
    this.work = { w: 300, h: 220 };
    this.paper = null;
    this.geom = null;
    this.boxes = [];
    this.travelBoxes = [];
    this.done = 0; // points drawn
    this.tail = null; // live pen position continuing the drawn part
    this.pen = null; // {x, y, down}
    this.picked = null; // {x, y}: the resume point picked on the drawing
    this.onPick = null; // called with {x, y} mm when the drawing is clicked
    this.view = null; // {scale (css px per mm), ox, oy (css px of machine 0,0)}
    this.userView = false; // the user panned or zoomed: keep their view
    this.dirty = false;
    this.scheduled = false;
    this.interactingUntil = 0;
    this.layersBuilt = 0; // complete static layers so far (tests wait for the first)
    this.pointers = new Map();
    this.frame = this.frame.bind(this);
    this.attachInput();
    new ResizeObserver(() => this.invalidate()).observe(canvas);
    this.invalidate();
  }

  // ---- data in ----

  setGeometry(geom) {
    if (geom === this.geom) return;
    this.geom = geom;
    this.boxes = geom ? chunkBoxes(geom.strokes) : [];
    this.travelBoxes = geom ? chunkBoxes(geom.travel) : [];
    this.geomVersion = (this.geomVersion || 0) + 1;
    this.done = 0;
    if (!this.pointers.size) { // never yank the view from under a drag or pinch
      this.userView = false;
      this.view = null; // fit the new drawing on the next render
    }
    this.invalidate();
  }

  setWorkArea(w, h) {
    if (w > 0 && h > 0 && (w !== this.work.w || h !== this.work.h)) {
      this.work = { w, h };
      if (!this.userView) this.view = null;
      this.invalidate();
    }
  }

  setPaper(rect) {
    const same = JSON.stringify(rect) === JSON.stringify(this.paper);
    if (!same) {
      this.paper = rect;
      this.invalidate();
    }
  }

  /** `points` reached; `tail` (the live pen) extends the drawn part into the next segment. */
  setDone(points, tail = null) {
    const t = this.tail;
    if (points !== this.done || !tail !== !t || (tail && (tail.x !== t.x || tail.y !== t.y))) {
      this.done = points;
      this.tail = tail;
      this.invalidate();
    }
  }

  setPicked(point) {
    const same = point === this.picked
      || (point && this.picked && point.x === this.picked.x && point.y === this.picked.y);
    if (!same) {
      this.picked = point;
      this.invalidate();
    }
  }

  setPen(pen) {
    const p = this.pen;
    if (!pen !== !p || (pen && (pen.x !== p.x || pen.y !== p.y || pen.down !== p.down))) {
      this.pen = pen;
      this.invalidate();
    }
  }

  // ---- view ----

  fitView() {
    const { width, height } = this.cssSize();
    const pad = 16;
    const w = this.work.w, h = this.work.h;
    const scale = Math.max(0.01, Math.min((width - 2 * pad) / w, (height - 2 * pad) / h));
    this.view = { scale, ox: (width - w * scale) / 2, oy: (height + h * scale) / 2 };
    this.userView = false;
    this.invalidate();
  }

  zoomAt(factor, cx, cy) {
    if (!this.view) this.fitView();
    const v = this.view;
    const scale = Math.min(2000, Math.max(0.05, v.scale * factor));
    const f = scale / v.scale;
    this.view = { scale, ox: cx - (cx - v.ox) * f, oy: cy - (cy - v.oy) * f };
    this.userView = true;
    this.interacted();
  }

  zoomCenter(factor) {
    const { width, height } = this.cssSize();
    this.zoomAt(factor, width / 2, height / 2);
  }

  panBy(dx, dy) {
    if (!this.view) this.fitView();
    this.view = { ...this.view, ox: this.view.ox + dx, oy: this.view.oy + dy };
    this.userView = true;
    this.interacted();
  }

  interacted() {
    this.interactingUntil = performance.now() + SETTLE_MS;
    this.invalidate();
    setTimeout(() => this.invalidate(), SETTLE_MS + 10);
  }

  cssSize() {
    return { width: this.canvas.clientWidth, height: this.canvas.clientHeight };
  }

  // ---- drawing ----

  invalidate() {
    this.dirty = true;
    if (!this.scheduled) {
      this.scheduled = true;
      requestAnimationFrame(this.frame);
    }
  }

  frame() {
    this.scheduled = false;
    // Hidden (another tab is shown): stay dirty; the ResizeObserver wakes us when shown.
    if (!this.dirty || !this.canvas.clientWidth) return;
    this.dirty = false;
    this.render();
  }

  /** Draw one frame; returns the time taken in ms (tests measure this). */
  render() {
    const t0 = performance.now();
    const { width, height } = this.cssSize();
    const dpr = window.devicePixelRatio || 1;
    const pw = Math.round(width * dpr), ph = Math.round(height * dpr);
    if (this.canvas.width !== pw || this.canvas.height !== ph) {
      this.canvas.width = pw;
      this.canvas.height = ph;
      if (!this.userView) this.view = null;
    }
    if (!this.view) this.fitView();
    const doneChunks = Math.floor(this.done / CHUNK);
    const key = [pw, ph, this.view.scale, this.view.ox, this.view.oy, doneChunks,
      this.work.w, this.work.h, JSON.stringify(this.paper), this.geomVersion].join();
    const interacting = performance.now() < this.interactingUntil;
    if (this.front?.key !== key && this.build?.key !== key && !(interacting && this.front)) {
      this.build = this.planStatic(key, pw, ph, dpr, doneChunks);
    }
    if (this.build && this.runBuild(t0 + FRAME_BUDGET_MS)) {
      const done = this.build;
      this.spare = this.front ? this.front.canvas : layerCanvas();
      this.front = { canvas: done.canvas, key: done.key, view: done.view };
      this.build = null;
      this.layersBuilt++;
    }
    const ctx = this.ctx;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    if (!this.front || this.front.canvas.width !== pw || this.front.canvas.height !== ph) {
      ctx.fillStyle = COLORS.background;
      ctx.fillRect(0, 0, pw, ph);
    } else if (this.front.key === key) {
      ctx.drawImage(this.front.canvas, 0, 0);
    } else {
      // the last complete layer, moved and scaled to the current view
      const v = this.view, fv = this.front.view;
      const f = v.scale / fv.scale;
      ctx.fillStyle = COLORS.background;
      ctx.fillRect(0, 0, pw, ph);
      ctx.setTransform(f, 0, 0, f, (v.ox - fv.ox * f) * dpr, (v.oy - fv.oy * f) * dpr);
      ctx.drawImage(this.front.canvas, 0, 0);
      ctx.setTransform(1, 0, 0, 1, 0, 0);
    }
    this.renderDynamic(dpr, doneChunks);
    if (this.build) this.invalidate(); // more of the layer next frame
    return performance.now() - t0;
  }

  /** Machine mm to device pixels: x' = a·x + e, y' = f − a·y. */
  deviceTransform(dpr) {
    const v = this.view;
    return { a: v.scale * dpr, e: v.ox * dpr, f: v.oy * dpr };
  }

  /** The static layer as a list of small steps, to be run a few per frame. */
  planStatic(key, pw, ph, dpr, doneChunks) {
    const canvas = this.spare;
    if (canvas.width !== pw || canvas.height !== ph) {
      canvas.width = pw;
      canvas.height = ph;
    }
    const ctx = canvas.getContext("2d");
    const t = this.deviceTransform(dpr);
    const visible = ([x0, y0, x1, y1]) => !(t.a * x1 + t.e < -4 || t.a * x0 + t.e > pw + 4
      || t.f - t.a * y0 < -4 || t.f - t.a * y1 > ph + 4);
    const rect = (r) => [t.a * r.x + t.e, t.f - t.a * (r.y + r.h), t.a * r.w, t.a * r.h];
    const steps = [() => {
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.fillStyle = COLORS.background;
      ctx.fillRect(0, 0, pw, ph);
      ctx.lineWidth = dpr;
      for (const [r, fill, edge] of [
        [{ x: 0, y: 0, w: this.work.w, h: this.work.h }, COLORS.work, COLORS.workEdge],
        [this.paper, COLORS.paper, COLORS.paperEdge],
      ]) {
        if (!r) continue;
        ctx.fillStyle = fill;
        ctx.fillRect(...rect(r));
        ctx.strokeStyle = edge;
        ctx.strokeRect(...rect(r));
      }
      const p = this.paper; // the margins, dashed inside the paper
      if (p && p.margin > 0 && p.w > 2 * p.margin && p.h > 2 * p.margin) {
        ctx.setLineDash([4 * dpr, 4 * dpr]);
        ctx.strokeRect(...rect({ x: p.x + p.margin, y: p.y + p.margin, w: p.w - 2 * p.margin, h: p.h - 2 * p.margin }));
        ctx.setLineDash([]);
      }
      ctx.lineWidth = LINE_PX;
    }];
    const g = this.geom;
    // runsOf(from, to): [[from, to, colour], ...] covering the chunk's points
    const chunkSteps = (set, boxes, runsOf) => boxes.forEach((box, c) => {
      if (!visible(box)) return;
      steps.push(() => {
        for (const [from, to, colour] of runsOf(c * CHUNK, Math.min(set.count, (c + 1) * CHUNK), c)) {
          const path = new Path2D();
          appendPath(path, set, from, to, t, MIN_PX);
          ctx.strokeStyle = colour;
          ctx.stroke(path);
        }
      });
    });
    if (g && g.fills.length) {
      // the shapes the SVG filled, tinted under the strokes (even-odd: holes stay clear)
      steps.push(() => {
        const path = new Path2D();
        for (const ring of g.fills) {
          ring.forEach(([x, y], i) => {
            if (i) path.lineTo(t.a * x + t.e, t.f - t.a * y);
            else path.moveTo(t.a * x + t.e, t.f - t.a * y);
          });
          path.closePath();
        }
        ctx.fillStyle = COLORS.filled;
        ctx.fill(path, "evenodd");
      });
    }
    if (g) {
      chunkSteps(g.travel, this.travelBoxes, (from, to) => [[from, to, COLORS.travel]]);
      // strokes still to draw in their layer's colour, the drawn part in one colour; the
      // partially drawn chunk is drawn per frame (renderDynamic), not here
      chunkSteps(g.strokes, this.boxes, (from, to, c) => {
        if (c === doneChunks) return [];
        return c < doneChunks ? [[from, to, COLORS.done]] : colourRunsIn(g.colours, from, to);
      });
    }
    return { key, view: { ...this.view }, canvas, ctx, steps, next: 0 };
  }

  /** Run build steps until `deadline`; true when the layer is complete. */
  runBuild(deadline) {
    const b = this.build;
    do {
      b.steps[b.next++]();
      // Rasterize each step now, inside this frame's budget (canvases defer drawing
      // until read or shown, which would put the whole layer's cost in one frame).
      b.ctx.getImageData(0, 0, 1, 1);
    } while (b.next < b.steps.length && performance.now() < deadline);
    return b.next >= b.steps.length;
  }

  renderDynamic(dpr, doneChunks) {
    const ctx = this.ctx;
    const t = this.deviceTransform(dpr);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    const first = doneChunks * CHUNK;
    const end = this.geom ? Math.min(this.geom.strokes.count, first + CHUNK) : 0;
    ctx.lineWidth = LINE_PX;
    for (const [from, to, colour] of end > this.done ? colourRunsIn(this.geom.colours, Math.max(first, this.done), end) : []) {
      const path = new Path2D(); // the partially drawn chunk's part still to draw
      appendPath(path, this.geom.strokes, from, to, t, MIN_PX);
      ctx.strokeStyle = colour;
      ctx.stroke(path);
    }
    if (this.geom && this.done > first) {
      const path = new Path2D();
      appendPath(path, this.geom.strokes, doneChunks * CHUNK, this.done, t, 0);
      if (this.tail) path.lineTo(t.a * this.tail.x + t.e, t.f - t.a * this.tail.y);
      ctx.lineWidth = LINE_PX;
      ctx.strokeStyle = COLORS.done;
      ctx.stroke(path);
    }
    if (this.picked) {
      const x = t.a * this.picked.x + t.e, y = t.f - t.a * this.picked.y;
      ctx.beginPath();
      ctx.arc(x, y, 5 * dpr, 0, 2 * Math.PI);
      ctx.fillStyle = COLORS.picked;
      ctx.fill();
    }
    if (this.pen) {
      const x = t.a * this.pen.x + t.e, y = t.f - t.a * this.pen.y;
      const r = 6 * dpr;
      ctx.beginPath();
      ctx.arc(x, y, r, 0, 2 * Math.PI);
      ctx.lineWidth = 2 * dpr;
      if (this.pen.down) {
        ctx.fillStyle = COLORS.penDown;
        ctx.fill();
      }
      ctx.strokeStyle = this.pen.down ? COLORS.penDown : COLORS.penUp;
      ctx.stroke();
      ctx.beginPath();
      ctx.moveTo(x - 2 * r, y);
      ctx.lineTo(x + 2 * r, y);
      ctx.moveTo(x, y - 2 * r);
      ctx.lineTo(x, y + 2 * r);
      ctx.lineWidth = dpr;
      ctx.stroke();
    }
  }

  // ---- input: drag to pan, wheel and pinch to zoom (pointer events everywhere) ----

  attachInput() {
    const c = this.canvas;
    c.style.touchAction = "none";
    const local = (e) => {
      const r = c.getBoundingClientRect();
      return { x: e.clientX - r.left, y: e.clientY - r.top };
    };
    c.addEventListener("pointerdown", (e) => {
      try {
        c.setPointerCapture(e.pointerId);
      } catch {
        // the pointer is already gone: nothing to capture
      }
      this.pointers.set(e.pointerId, local(e));
      this.pressed = this.pointers.size === 1 ? local(e) : null;
    });
    c.addEventListener("pointermove", (e) => {
      const prev = this.pointers.get(e.pointerId);
      if (!prev) return;
      const now = local(e);
      if (this.pointers.size === 1) {
        this.panBy(now.x - prev.x, now.y - prev.y);
      } else if (this.pointers.size === 2) {
        const [other] = [...this.pointers.entries()].filter(([id]) => id !== e.pointerId);
        const o = other[1];
        const before = Math.hypot(prev.x - o.x, prev.y - o.y);
        const after = Math.hypot(now.x - o.x, now.y - o.y);
        if (before > 0) this.zoomAt(after / before, (now.x + o.x) / 2, (now.y + o.y) / 2);
      }
      this.pointers.set(e.pointerId, now);
    });
    const up = (e) => this.pointers.delete(e.pointerId);
    c.addEventListener("pointerup", (e) => {
      const p = local(e), from = this.pressed;
      this.pressed = null;
      up(e);
      if (from && this.view && this.onPick && Math.hypot(p.x - from.x, p.y - from.y) < CLICK_PX) {
        const v = this.view;
        this.onPick({ x: (p.x - v.ox) / v.scale, y: (v.oy - p.y) / v.scale, tolerance: PICK_PX / v.scale });
      }
    });
    c.addEventListener("pointercancel", up);
    c.addEventListener("wheel", (e) => {
      e.preventDefault();
      const p = local(e);
      const unit = e.deltaMode === 1 ? 16 : 1;
      this.zoomAt(Math.exp(-e.deltaY * unit * 0.0015), p.x, p.y);
    }, { passive: false });
    c.addEventListener("dblclick", () => this.fitView());
  }
}
