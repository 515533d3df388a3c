// The preview canvas: work area, paper, strokes, pen-up travel, the drawn part and
// the live pen. Redraws happen in requestAnimationFrame, only when something changed.
// Speed for 200,000 points: paths are built in device pixels, dropping points closer
// than MIN_PX to the last one kept and chunks outside the view, then stroked in one
// call per colour; the static layer (all but the partially drawn chunk and the pen) is
// cached in a second canvas and re-rendered only when the view, the data or a whole
// chunk of progress changed; while panning or zooming the cached bitmap is moved.

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
};
const SETTLE_MS = 120; // after the last pan/zoom event, re-render crisp
const MIN_PX = 0.6; // device pixels: closer points are not visible apart
// Strokes are one device pixel wide: browsers rasterize such hairlines far faster
// (Chromium's software canvas: 12 ms instead of 330 ms for 200,000 points).
const LINE_PX = 1;

/** Bounding box [minX, minY, maxX, maxY] of each CHUNK points (with the joining point). */
export function chunkBoxes(set) {
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

export class PreviewCanvas {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.cache = document.createElement("canvas");
    this.cacheCtx = this.cache.getContext("2d");
    this.cacheKey = "";
    this.cacheView = null;
    this.work = { w: 300, h: 220 };
    this.paper = null;
    this.geom = null;
    this.boxes = [];
    this.travelBoxes = [];
    this.done = 0; // points drawn
    this.tail = null; // live pen position continuing the drawn part
    this.pen = null; // {x, y, down}
    this.view = null; // {scale (css px per mm), ox, oy (css px of machine 0,0)}
    this.userView = false; // the user panned or zoomed: keep their view
    this.dirty = false;
    this.scheduled = false;
    this.interactingUntil = 0;
    this.stats = { frames: 0, lastMs: 0, maxMs: 0, fullRenders: 0, lastFullMs: 0 };
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
    this.userView = false;
    this.view = null; // fit the new drawing on the next render
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
    return { width: this.canvas.clientWidth || 300, height: this.canvas.clientHeight || 220 };
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
    if (!this.dirty) return;
    this.dirty = false;
    const ms = this.render();
    this.stats.frames++;
    this.stats.lastMs = ms;
    this.stats.maxMs = Math.max(this.stats.maxMs, ms);
  }

  /** Draw now; returns the time taken in ms (tests and the benchmark call this). */
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
    const ctx = this.ctx;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    const interacting = performance.now() < this.interactingUntil;
    if (key !== this.cacheKey && interacting && this.cacheView && this.cache.width === pw) {
      // While panning/zooming, move the cached bitmap; the crisp render follows.
      const f = this.view.scale / this.cacheView.scale;
      ctx.fillStyle = COLORS.background;
      ctx.fillRect(0, 0, pw, ph);
      ctx.setTransform(f, 0, 0, f,
        (this.view.ox - this.cacheView.ox * f) * dpr, (this.view.oy - this.cacheView.oy * f) * dpr);
      ctx.drawImage(this.cache, 0, 0);
      ctx.setTransform(1, 0, 0, 1, 0, 0);
    } else {
      if (key !== this.cacheKey) {
        this.renderStatic(pw, ph, dpr, doneChunks);
        this.cacheKey = key;
        this.cacheView = { ...this.view };
      }
      ctx.drawImage(this.cache, 0, 0);
      this.renderDynamic(dpr, doneChunks);
    }
    return performance.now() - t0;
  }

  /** Machine mm to device pixels: x' = a·x + e, y' = f − a·y. */
  deviceTransform(dpr) {
    const v = this.view;
    return { a: v.scale * dpr, e: v.ox * dpr, f: v.oy * dpr };
  }

  /** One path over the visible chunks [fromChunk, toChunk) of a point set. */
  chunksPath(set, boxes, fromChunk, toChunk, t, pw, ph) {
    const path = new Path2D();
    const margin = 4;
    for (let c = fromChunk; c < toChunk; c++) {
      const [x0, y0, x1, y1] = boxes[c];
      if (t.a * x1 + t.e < -margin || t.a * x0 + t.e > pw + margin
        || t.f - t.a * y0 < -margin || t.f - t.a * y1 > ph + margin) continue;
      appendPath(path, set, c * CHUNK, Math.min(set.count, (c + 1) * CHUNK), t, MIN_PX);
    }
    return path;
  }

  renderStatic(pw, ph, dpr, doneChunks) {
    const t0 = performance.now();
    if (this.cache.width !== pw || this.cache.height !== ph) {
      this.cache.width = pw;
      this.cache.height = ph;
    }
    const ctx = this.cacheCtx;
    const t = this.deviceTransform(dpr);
    const rect = (x, y, w, h) => [t.a * x + t.e, t.f - t.a * (y + h), t.a * w, t.a * h];
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = COLORS.background;
    ctx.fillRect(0, 0, pw, ph);
    ctx.fillStyle = COLORS.work;
    ctx.fillRect(...rect(0, 0, this.work.w, this.work.h));
    ctx.lineWidth = dpr;
    ctx.strokeStyle = COLORS.workEdge;
    ctx.strokeRect(...rect(0, 0, this.work.w, this.work.h));
    if (this.paper) {
      const p = this.paper;
      ctx.fillStyle = COLORS.paper;
      ctx.fillRect(...rect(p.x, p.y, p.w, p.h));
      ctx.strokeStyle = COLORS.paperEdge;
      ctx.strokeRect(...rect(p.x, p.y, p.w, p.h));
    }
    const g = this.geom;
    if (g) {
      ctx.strokeStyle = COLORS.travel;
      ctx.lineWidth = LINE_PX;
      ctx.stroke(this.chunksPath(g.travel, this.travelBoxes, 0, this.travelBoxes.length, t, pw, ph));
      ctx.lineWidth = LINE_PX;
      const split = Math.min(doneChunks, this.boxes.length);
      ctx.strokeStyle = COLORS.done;
      ctx.stroke(this.chunksPath(g.strokes, this.boxes, 0, split, t, pw, ph));
      ctx.strokeStyle = COLORS.todo;
      ctx.stroke(this.chunksPath(g.strokes, this.boxes, split, this.boxes.length, t, pw, ph));
    }
    this.stats.fullRenders++;
    this.stats.lastFullMs = performance.now() - t0;
  }

  renderDynamic(dpr, doneChunks) {
    const ctx = this.ctx;
    const t = this.deviceTransform(dpr);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    if (this.geom && this.done > doneChunks * CHUNK) {
      const path = new Path2D();
      appendPath(path, this.geom.strokes, doneChunks * CHUNK, this.done, t, 0);
      if (this.tail) path.lineTo(t.a * this.tail.x + t.e, t.f - t.a * this.tail.y);
      ctx.lineWidth = LINE_PX;
      ctx.strokeStyle = COLORS.done;
      ctx.stroke(path);
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
      c.setPointerCapture(e.pointerId);
      this.pointers.set(e.pointerId, local(e));
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
    c.addEventListener("pointerup", up);
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
