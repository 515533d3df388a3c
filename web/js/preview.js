// The preview canvas: work area, paper, strokes, pen-up travel, the drawn part and
// the live pen. Strokes are cached as one Path2D per CHUNK points; the static layer
// (everything but the partially drawn chunk and the pen) is cached in a second canvas
// and only re-rendered when the view, the data or a whole chunk of progress changed.
// Redraws happen in requestAnimationFrame, only when something changed.

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

function chunkPaths(set) {
  const { coords, starts, count } = set;
  const paths = [];
  let stroke = 0;
  for (let c = 0; c * CHUNK < count; c++) {
    const first = c * CHUNK;
    const last = Math.min(count, first + CHUNK); // exclusive
    const path = new Path2D();
    while (starts[stroke + 1] <= first) stroke++;
    // continue the stroke from the previous chunk's last point
    let i = first > starts[stroke] ? first - 1 : first;
    path.moveTo(coords[2 * i], coords[2 * i + 1]);
    for (i += 1; i < last; i++) {
      if (i === starts[stroke + 1]) {
        stroke++;
        path.moveTo(coords[2 * i], coords[2 * i + 1]);
      } else {
        path.lineTo(coords[2 * i], coords[2 * i + 1]);
      }
    }
    paths.push(path);
  }
  return paths;
}

/** Path of stroke segments whose both ends are in [from, to). */
function rangePath(set, from, to) {
  const { coords, starts } = set;
  const path = new Path2D();
  if (to - from < 2) return path;
  // stroke containing `from`: binary search in starts
  let lo = 0, hi = starts.length - 2;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (starts[mid] <= from) lo = mid;
    else hi = mid - 1;
  }
  let stroke = lo;
  path.moveTo(coords[2 * from], coords[2 * from + 1]);
  for (let i = from + 1; i < to; i++) {
    if (i === starts[stroke + 1]) {
      stroke++;
      path.moveTo(coords[2 * i], coords[2 * i + 1]);
    } else {
      path.lineTo(coords[2 * i], coords[2 * i + 1]);
    }
  }
  return path;
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
    this.strokePaths = [];
    this.travelPath = null;
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
    this.strokePaths = geom ? chunkPaths(geom.strokes) : [];
    this.travelPath = geom && geom.travel.count ? rangePath(geom.travel, 0, geom.travel.count) : null;
    this.done = 0;
    this.userView = false;
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
      this.work.w, this.work.h, JSON.stringify(this.paper), this.strokePaths.length].join();
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

  toMachine(ctx, dpr) {
    const v = this.view;
    ctx.setTransform(v.scale * dpr, 0, 0, -v.scale * dpr, v.ox * dpr, v.oy * dpr);
  }

  renderStatic(pw, ph, dpr, doneChunks) {
    const t0 = performance.now();
    if (this.cache.width !== pw || this.cache.height !== ph) {
      this.cache.width = pw;
      this.cache.height = ph;
    }
    const ctx = this.cacheCtx;
    const px = 1 / this.view.scale; // one CSS pixel in mm
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = COLORS.background;
    ctx.fillRect(0, 0, pw, ph);
    this.toMachine(ctx, dpr);
    ctx.fillStyle = COLORS.work;
    ctx.fillRect(0, 0, this.work.w, this.work.h);
    ctx.lineWidth = px;
    ctx.strokeStyle = COLORS.workEdge;
    ctx.strokeRect(0, 0, this.work.w, this.work.h);
    if (this.paper) {
      const p = this.paper;
      ctx.fillStyle = COLORS.paper;
      ctx.fillRect(p.x, p.y, p.w, p.h);
      ctx.strokeStyle = COLORS.paperEdge;
      ctx.strokeRect(p.x, p.y, p.w, p.h);
    }
    ctx.lineJoin = "round";
    ctx.lineCap = "round";
    if (this.travelPath) {
      ctx.strokeStyle = COLORS.travel;
      ctx.lineWidth = px;
      ctx.stroke(this.travelPath);
    }
    ctx.lineWidth = 1.25 * px;
    this.strokePaths.forEach((path, c) => {
      ctx.strokeStyle = c < doneChunks ? COLORS.done : COLORS.todo;
      ctx.stroke(path);
    });
    this.stats.fullRenders++;
    this.stats.lastFullMs = performance.now() - t0;
  }

  renderDynamic(dpr, doneChunks) {
    const ctx = this.ctx;
    const px = 1 / this.view.scale;
    this.toMachine(ctx, dpr);
    if (this.geom && this.done > doneChunks * CHUNK) {
      const from = Math.max(0, doneChunks * CHUNK - 1);
      ctx.lineJoin = "round";
      ctx.lineCap = "round";
      ctx.lineWidth = 1.25 * px;
      ctx.strokeStyle = COLORS.done;
      const path = rangePath(this.geom.strokes, from, this.done);
      if (this.tail) path.lineTo(this.tail.x, this.tail.y);
      ctx.stroke(path);
    }
    if (this.pen) {
      const r = 6 * px;
      ctx.beginPath();
      ctx.arc(this.pen.x, this.pen.y, r, 0, 2 * Math.PI);
      ctx.lineWidth = 2 * px;
      if (this.pen.down) {
        ctx.fillStyle = COLORS.penDown;
        ctx.fill();
      }
      ctx.strokeStyle = this.pen.down ? COLORS.penDown : COLORS.penUp;
      ctx.stroke();
      ctx.beginPath();
      ctx.moveTo(this.pen.x - 2 * r, this.pen.y);
      ctx.lineTo(this.pen.x + 2 * r, this.pen.y);
      ctx.moveTo(this.pen.x, this.pen.y - 2 * r);
      ctx.lineTo(this.pen.x, this.pen.y + 2 * r);
      ctx.lineWidth = px;
      ctx.stroke();
    }
    ctx.setTransform(1, 0, 0, 1, 0, 0);
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
