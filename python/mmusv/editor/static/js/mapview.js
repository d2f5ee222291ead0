// The top-down map: an SVG with a world group (metres, x east, y north, drawn at true scale) and a screen group
// (handles, markers, labels in pixels). View: the world point (cx, cy) at the centre of the SVG, `scale` pixels
// per metre; screen x = w/2 + (x - cx)·scale, screen y = h/2 - (y - cy)·scale (north up).

const NS = "http://www.w3.org/2000/svg";
const MIN_SCALE = 0.01;
const MAX_SCALE = 60;
const CLICK_SLOP_PX = 4;

function el(tag, attrs = {}, parent = null) {
  const node = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

function pathOf(points, close = false) {
  if (!points.length) return "";
  let d = `M${points[0][0]},${points[0][1]}`;
  for (let i = 1; i < points.length; i++) d += `L${points[i][0]},${points[i][1]}`;
  return close ? d + "Z" : d;
}

/** Hull outline (bow at +x) of a vessel `length` x `beam` at pose [x, y, yaw], world metres. */
export function hullOutline(length, beam, [x, y, yaw]) {
  const l2 = length / 2, b2 = beam / 2, bow = Math.min(0.3 * length, 0.9 * beam);
  const body = [[l2, 0], [l2 - bow, b2], [-l2, b2], [-l2, -b2], [l2 - bow, -b2]];
  const c = Math.cos(yaw), s = Math.sin(yaw);
  return body.map(([u, v]) => [x + c * u - s * v, y + s * u + c * v]);
}

function niceStep(raw) {
  const base = 10 ** Math.floor(Math.log10(raw));
  return [1, 2, 5, 10].map((k) => k * base).find((v) => v >= raw);
}

export class MapView {
  constructor(state, svg) {
    this.state = state;
    this.svg = svg;
    this.world = svg.querySelector("#world");
    this.screen = svg.querySelector("#screen");
    this.layers = {};
    for (const name of ["map", "rings", "routes", "checks", "sailed", "hulls"]) {
      this.layers[name] = el("g", { id: `layer-${name}` }, this.world);
    }
    for (const name of ["flags", "markers", "handles", "labels"]) {
      this.layers[name] = el("g", { id: `layer-${name}` }, this.screen);
    }
    this.view = { cx: 0, cy: 0, scale: 0.4 };
    this.mode = "select"; // select | place | draw
    this.placing = null; // {asset, role}
    this.activeWaypoint = null; // {vessel, index}
    this.gesture = null;
    this.gestureCount = 0;
    this.bindEvents();
    new ResizeObserver(() => this.applyView()).observe(svg);
  }

  // ----------------------------------------------------------------------------------------- transforms

  size() {
    const r = this.svg.getBoundingClientRect();
    return { w: r.width, h: r.height, left: r.left, top: r.top };
  }

  toScreen(x, y) {
    const { w, h } = this.size();
    const { cx, cy, scale } = this.view;
    return [w / 2 + (x - cx) * scale, h / 2 - (y - cy) * scale];
  }

  toWorld(px, py) {
    const { w, h } = this.size();
    const { cx, cy, scale } = this.view;
    return [cx + (px - w / 2) / scale, cy - (py - h / 2) / scale];
  }

  eventWorld(ev) {
    const { left, top } = this.size();
    return this.toWorld(ev.clientX - left, ev.clientY - top);
  }

  applyView() {
    const { w, h } = this.size();
    const { cx, cy, scale } = this.view;
    this.world.setAttribute("transform", `translate(${w / 2 - cx * scale},${h / 2 + cy * scale}) scale(${scale},${-scale})`);
    this.renderScreen();
    this.renderScale();
    this.state.emit("view");
  }

  zoomAt(factor, px, py) {
    const [wx, wy] = this.toWorld(px, py);
    const scale = Math.min(MAX_SCALE, Math.max(MIN_SCALE, this.view.scale * factor));
    const { w, h } = this.size();
    this.view = { scale, cx: wx - (px - w / 2) / scale, cy: wy + (py - h / 2) / scale };
    this.applyView();
  }

  fitBox(x0, y0, x1, y1, margin = 40) {
    const { w, h } = this.size();
    if (w <= 0 || h <= 0) return;
    const sx = (w - 2 * margin) / Math.max(x1 - x0, 1);
    const sy = (h - 2 * margin) / Math.max(y1 - y0, 1);
    this.view = {
      cx: (x0 + x1) / 2,
      cy: (y0 + y1) / 2,
      scale: Math.min(MAX_SCALE, Math.max(MIN_SCALE, Math.min(sx, sy))),
    };
    this.applyView();
  }

  fitMap() {
    const b = this.state.mapLayers?.bounds;
    if (b) this.fitBox(b[0], b[1], b[2], b[3], 10);
  }

  fitScenario() {
    const pts = [];
    for (const v of this.state.doc?.vessels || []) for (const p of v.route || []) pts.push(p);
    const ev = this.state.lastGood;
    for (const v of ev?.vessels || []) for (const p of v.path) pts.push(p);
    if (!pts.length) return this.fitMap();
    const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
    const pad = 60;
    this.fitBox(Math.min(...xs) - pad, Math.min(...ys) - pad, Math.max(...xs) + pad, Math.max(...ys) + pad);
  }

  zoomTo(id) {
    const v = this.state.vessel(id);
    if (!v?.route?.length) return;
    const xs = v.route.map((p) => p[0]), ys = v.route.map((p) => p[1]);
    this.fitBox(Math.min(...xs) - 80, Math.min(...ys) - 80, Math.max(...xs) + 80, Math.max(...ys) + 80);
  }

  // ----------------------------------------------------------------------------------------- rendering

  renderMap() {
    const g = this.layers.map;
    g.replaceChildren();
    const m = this.state.mapLayers;
    if (!m) return;
    const [x0, y0, x1, y1] = m.bounds;
    const flip = el("g", { transform: "scale(1,-1)" }, g);
    el("image", { href: m.image, x: x0, y: -y1, width: x1 - x0, height: y1 - y0, preserveAspectRatio: "none", id: "map-image" }, flip);
    el("rect", { class: "bounds", x: x0, y: y0, width: x1 - x0, height: y1 - y0 }, g);
    for (const line of m.shoreline) el("path", { class: "shore", d: pathOf(line) }, g);
    for (const rings of m.structures) el("path", { class: "structure", d: rings.map((r) => pathOf(r, true)).join("") }, g);
    for (const ship of m.moored) {
      const p = el("path", { class: "moored", d: pathOf(ship.outline, true) }, g);
      el("title", {}, p).textContent = `moored ${ship.asset} (${ship.length} × ${ship.beam} m)`;
    }
    for (const [x, y] of m.buoys) el("circle", { class: "buoy", cx: x, cy: y, r: 2.5 }, g);
  }

  /** Evaluation data of the vessel `id` (route samples, poses, rings), from the latest evaluation that had them. */
  evalVessel(id) {
    const ev = this.state.evaluation?.valid ? this.state.evaluation : this.state.evaluation ? null : this.state.lastGood;
    return ev?.vessels.find((v) => v.id === id) || null;
  }

  renderScenario() {
    const { routes, rings, checks, sailed } = this.layers;
    routes.replaceChildren();
    rings.replaceChildren();
    checks.replaceChildren();
    sailed.replaceChildren();
    const doc = this.state.doc;
    if (!doc) return;
    const ev = this.state.evaluation?.valid ? this.state.evaluation : this.state.evaluation ? null : this.state.lastGood;
    for (const v of doc.vessels || []) {
      const e = ev?.vessels.find((x) => x.id === v.id);
      const cls = v.role === "usv" ? "usv" : "target";
      const selected = v.id === this.state.selected ? " selected" : "";
      const pts = e ? e.path : v.route || [];
      const attrs = { class: `route ${cls}${selected}${e ? "" : " unevaluated"}`, d: pathOf(pts), "data-vessel": v.id };
      el("path", attrs, routes);
      const hit = el("path", { class: "route-hit", d: pathOf(pts), "data-vessel": v.id }, routes);
      hit.dataset.vessel = v.id;
      if (e?.poses) el("path", { class: "sailed", d: pathOf(e.poses.map((p) => [p[0], p[1]])), "data-vessel": v.id }, sailed);
    }
    const drawOrder = [...(ev?.problems || [])].sort((a, b) => (a.severity === "error") - (b.severity === "error"));
    for (const p of drawOrder) { // errors last, on top
      for (const [vid, runs] of Object.entries(p.segments || {})) {
        const e = ev.vessels.find((x) => x.id === vid);
        if (!e) continue;
        for (const [a, b] of runs) {
          const seg = e.path.slice(Math.max(0, a - 1), Math.min(e.path.length, b + 2));
          el("path", {
            class: p.severity === "error" ? "route-bad" : "route-warn",
            d: pathOf(seg),
            "data-vessel": vid,
            "data-check": p.check,
          }, checks);
        }
      }
    }
    this.renderRings();
    this.renderFrame();
  }

  renderRings() {
    const g = this.layers.rings;
    g.replaceChildren();
    const poses = this.state.posesAt();
    const ev = this.state.evaluation?.valid ? this.state.evaluation : null;
    if (!ev || !poses) return;
    ev.vessels.forEach((v, i) => {
      if (!v.rings || !poses[i]) return;
      const [x, y] = poses[i];
      if (v.rings.radar) el("circle", { class: "ring-radar", cx: x, cy: y, r: v.rings.radar, "data-vessel": v.id }, g);
      if (v.rings.lidar) el("circle", { class: "ring-lidar", cx: x, cy: y, r: v.rings.lidar, "data-vessel": v.id }, g);
    });
  }

  /** Vessel positions at the current frame: [{id, role, pose, length, beam, evaluated}] in document order. */
  positions() {
    const doc = this.state.doc;
    const ev = this.state.evaluation?.valid ? this.state.evaluation : null;
    const poses = this.state.posesAt();
    const assets = new Map(this.state.assets.map((a) => [a.name, a]));
    const out = [];
    (doc?.vessels || []).forEach((v, i) => {
      const a = assets.get(v.asset);
      if (ev && poses && ev.vessels[i]?.id === v.id && poses[i]) {
        out.push({ id: v.id, role: v.role, pose: poses[i], length: ev.vessels[i].length, beam: ev.vessels[i].beam, evaluated: true });
      } else if (v.route?.length) {
        const [p, q] = [v.route[0], v.route[1] || [v.route[0][0] + 1, v.route[0][1]]];
        const yaw = Math.atan2(q[1] - p[1], q[0] - p[0]);
        out.push({ id: v.id, role: v.role, pose: [p[0], p[1], yaw], length: a?.length || 10, beam: a?.beam || 4, evaluated: false });
      }
    });
    return out;
  }

  renderFrame() {
    const g = this.layers.hulls;
    g.replaceChildren();
    for (const p of this.positions()) {
      const cls = p.role === "usv" ? "usv" : "target";
      el("path", { class: `hull ${cls}`, d: pathOf(hullOutline(p.length, p.beam, p.pose), true), "data-vessel": p.id }, g);
    }
    this.renderRings();
    this.renderScreen();
  }

  renderScreen() {
    const { flags, markers, handles, labels } = this.layers;
    flags.replaceChildren();
    markers.replaceChildren();
    handles.replaceChildren();
    labels.replaceChildren();
    const doc = this.state.doc;
    if (!doc) return;
    const flagged = new Map(); // id -> severity
    const ev = this.state.evaluation;
    for (const p of ev?.problems || []) {
      for (const id of p.vessels) if (flagged.get(id) !== "error") flagged.set(id, p.severity);
      if (p.point) {
        const [sx, sy] = this.toScreen(p.point[0], p.point[1]);
        el("rect", {
          class: `problem-point ${p.severity}`,
          x: sx - 4, y: sy - 4, width: 8, height: 8,
          transform: `rotate(45 ${sx} ${sy})`,
          "data-check": p.check,
        }, flags);
      }
    }
    for (const e of ev?.errors || []) if (e.vessel) flagged.set(e.vessel, "error");
    for (const p of this.positions()) {
      const [sx, sy] = this.toScreen(p.pose[0], p.pose[1]);
      const cls = p.role === "usv" ? "usv" : "target";
      const sel = p.id === this.state.selected ? " selected" : "";
      const marker = el("circle", {
        class: `vessel-marker ${cls}${sel}`,
        cx: sx, cy: sy, r: 5.5,
        "data-id": p.id,
        "data-x": p.pose[0], "data-y": p.pose[1],
        "data-evaluated": p.evaluated ? "1" : "0",
      }, markers);
      marker.dataset.id = p.id;
      if (flagged.has(p.id)) {
        el("circle", { class: `vessel-flag ${flagged.get(p.id)}`, cx: sx, cy: sy, r: 11, "data-id": p.id }, flags);
      }
      const label = el("text", { class: "vessel-label", x: sx + 9, y: sy - 8 }, labels);
      label.textContent = p.id;
    }
    const m = this.state.mapLayers;
    if (m && this.view.scale > 0.6) {
      const overlays = this.overlayRects();
      for (const ship of m.moored) {
        const [sx, sy] = this.toScreen(ship.x, ship.y);
        const t = el("text", { class: "moored-label", x: sx - 20, y: sy + 4 }, labels);
        t.textContent = ship.asset;
        // A label at the top of the map that would sit under the map buttons (or the legend) moves down to
        // just below them, so it stays readable.
        const b = t.getBBox();
        for (const o of overlays) {
          if (b.x < o.x1 && b.x + b.width > o.x0 && b.y < o.y1 && b.y + b.height > o.y0) {
            t.setAttribute("y", o.y1 + (sy + 4 - b.y));
          }
        }
      }
    }
    const v = this.state.vessel();
    if (v) {
      (v.route || []).forEach(([x, y], i) => {
        const [sx, sy] = this.toScreen(x, y);
        const active = this.activeWaypoint?.vessel === v.id && this.activeWaypoint.index === i ? " active" : "";
        const h = el("circle", {
          class: `waypoint ${v.role === "usv" ? "usv" : "target"}${i === 0 ? " first" : ""}${active}`,
          cx: sx, cy: sy, r: 6,
          "data-vessel": v.id, "data-index": i,
        }, handles);
        el("title", {}, h).textContent = `${v.id} waypoint ${i}: (${x}, ${y}) m · drag to move · right-click to delete`;
      });
    }
  }

  /** Rectangles (SVG pixels, with a 4 px margin) of the controls drawn over the map: the Fit/Map/+/− buttons
   * and the legend. Hidden controls are left out. */
  overlayRects() {
    const base = this.svg.getBoundingClientRect();
    const out = [];
    for (const id of ["map-tools", "legend"]) {
      const r = document.getElementById(id)?.getBoundingClientRect();
      if (!r || r.width === 0 || r.height === 0) continue;
      out.push({ x0: r.left - base.left - 4, y0: r.top - base.top - 4, x1: r.right - base.left + 4, y1: r.bottom - base.top + 4 });
    }
    return out;
  }

  renderScale() {
    const target = 120 / this.view.scale; // metres in ~120 px
    const step = niceStep(target);
    document.getElementById("scale-bar").style.width = `${step * this.view.scale}px`;
    document.getElementById("scale-text").textContent = step >= 1000 ? `${step / 1000} km` : `${step} m`;
  }

  // ----------------------------------------------------------------------------------------- editing

  setMode(mode, extra = {}) {
    this.mode = mode;
    this.placing = mode === "place" ? extra : null;
    this.drawing = mode === "draw" ? extra.vessel : null; // the vessel whose route is being drawn
    this.svg.classList.toggle("placing", mode === "place");
    this.svg.classList.toggle("drawing", mode === "draw");
    this.state.emit("mode", { mode, ...extra });
  }

  newVesselId(role) {
    const base = role === "usv" ? "usv" : "target";
    const ids = new Set((this.state.doc.vessels || []).map((v) => v.id));
    let n = 1;
    while (ids.has(`${base}_${n}`)) n++;
    return `${base}_${n}`;
  }

  /** The world point (metres) under the middle of the map, where the keyboard places and adds waypoints. */
  centre() {
    return [this.view.cx, this.view.cy];
  }

  round(p) {
    return [Math.round(p[0] * 10) / 10, Math.round(p[1] * 10) / 10];
  }

  place(point) {
    const { asset, role: wanted } = this.placing;
    const role = wanted === "auto" ? (asset.usv ? "usv" : "target") : wanted;
    const id = this.newVesselId(role);
    this.state.edit((doc) => {
      const v = { id, role, asset: asset.name, speed_mps: 3, route: [this.round(point)] };
      if (role === "usv") {
        doc.rigs ||= {};
        let rig = Object.keys(doc.rigs)[0];
        if (!rig) {
          rig = "usv_standard";
          doc.rigs[rig] = {};
        }
        v.rig = rig;
        v.role = "usv";
      }
      doc.vessels ||= [];
      doc.vessels.push(v);
    });
    this.state.select(id);
    this.setMode("draw", { vessel: id });
  }

  appendWaypoint(point) {
    const id = this.state.selected;
    const v = this.state.vessel(id);
    if (!v) return this.setMode("select");
    const last = v.route[v.route.length - 1];
    if (last) {
      const [a, b] = [this.toScreen(...last), this.toScreen(...point)];
      if (Math.hypot(a[0] - b[0], a[1] - b[1]) < CLICK_SLOP_PX) return; // the second click of a double-click
    }
    this.state.edit((doc) => doc.vessels[this.state.vesselIndex(id)].route.push(this.round(point)));
  }

  insertWaypoint(id, point) {
    const v = this.state.vessel(id);
    if (!v || v.route.length < 2) return;
    let best = 0, bestD = Infinity;
    for (let i = 0; i + 1 < v.route.length; i++) {
      const [a, b] = [v.route[i], v.route[i + 1]];
      const dx = b[0] - a[0], dy = b[1] - a[1];
      const t = Math.max(0, Math.min(1, ((point[0] - a[0]) * dx + (point[1] - a[1]) * dy) / (dx * dx + dy * dy || 1)));
      const d = Math.hypot(a[0] + t * dx - point[0], a[1] + t * dy - point[1]);
      if (d < bestD) [best, bestD] = [i, d];
    }
    this.state.edit((doc) => doc.vessels[this.state.vesselIndex(id)].route.splice(best + 1, 0, this.round(point)));
    this.activeWaypoint = { vessel: id, index: best + 1 };
  }

  deleteWaypoint(id, index) {
    this.activeWaypoint = null;
    const v = this.state.vessel(id);
    if (!v || !Array.isArray(v.route) || !(index >= 0 && index < v.route.length)) return; // gone meanwhile
    if (v.route.length <= 2) {
      // a route of one point is no route: deleting down to it left the file invalid (a review's)
      this.state.emit("status", {
        text: `${id}'s route has ${v.route.length} waypoints, the fewest a route has: move this one instead, or delete the vessel`,
        error: true,
      });
      return;
    }
    this.state.edit((doc) => doc.vessels[this.state.vesselIndex(id)].route.splice(index, 1));
  }

  // ----------------------------------------------------------------------------------------- events

  bindEvents() {
    const svg = this.svg;
    svg.addEventListener("wheel", (ev) => {
      ev.preventDefault();
      const { left, top } = this.size();
      this.zoomAt(Math.exp(-ev.deltaY * 0.0015), ev.clientX - left, ev.clientY - top);
    }, { passive: false });

    svg.addEventListener("pointerdown", (ev) => {
      if (ev.button !== 0) return;
      svg.focus();
      const t = ev.target;
      this.downTarget = t; // with the pointer captured, click and dblclick target the SVG itself
      const start = { x: ev.clientX, y: ev.clientY, moved: false };
      if (t.classList.contains("waypoint")) {
        const vessel = t.getAttribute("data-vessel"), index = Number(t.getAttribute("data-index"));
        this.activeWaypoint = { vessel, index };
        this.gesture = { kind: "waypoint", vessel, index, start, id: `wp${++this.gestureCount}` };
      } else if (t.classList.contains("vessel-marker")) {
        this.state.select(t.getAttribute("data-id"));
        this.gesture = { kind: "none", start };
      } else if (this.mode === "select" && t.classList.contains("route-hit")) {
        this.state.select(t.getAttribute("data-vessel"));
        this.gesture = { kind: "pan", start, view: { ...this.view } };
      } else {
        this.gesture = { kind: "pan", start, view: { ...this.view } };
      }
      svg.setPointerCapture(ev.pointerId);
    });

    svg.addEventListener("pointermove", (ev) => {
      const [wx, wy] = this.eventWorld(ev);
      document.getElementById("cursor").textContent = `x ${wx.toFixed(1)} m · y ${wy.toFixed(1)} m`;
      const g = this.gesture;
      if (!g) return;
      if (Math.hypot(ev.clientX - g.start.x, ev.clientY - g.start.y) > CLICK_SLOP_PX) g.start.moved = true;
      if (!g.start.moved) return;
      if (g.kind === "waypoint") {
        const p = this.round([wx, wy]);
        this.state.edit((doc) => {
          doc.vessels[this.state.vesselIndex(g.vessel)].route[g.index] = p;
        }, { gesture: g.id });
      } else if (g.kind === "pan") {
        svg.classList.add("panning");
        const s = g.view.scale;
        this.view = { scale: s, cx: g.view.cx - (ev.clientX - g.start.x) / s, cy: g.view.cy + (ev.clientY - g.start.y) / s };
        this.applyView();
      }
    });

    const end = (ev) => {
      const g = this.gesture;
      this.gesture = null;
      svg.classList.remove("panning");
      if (!g || g.start.moved || ev.type === "pointercancel") return;
      if (g.kind === "pan") {
        const p = this.eventWorld(ev);
        if (this.mode === "place") this.place(p);
        else if (this.mode === "draw") this.appendWaypoint(p);
        else if (!this.downTarget?.classList.contains("route-hit")) {
          this.activeWaypoint = null;
          this.state.select(null);
        }
      } else if (g.kind === "waypoint") {
        this.renderScreen();
      }
    };
    svg.addEventListener("pointerup", end);
    svg.addEventListener("pointercancel", end);

    svg.addEventListener("dblclick", (ev) => {
      if (this.mode === "draw") {
        this.setMode("select");
        return;
      }
      const t = this.downTarget || ev.target;
      if (t.classList.contains("route-hit")) {
        const id = t.getAttribute("data-vessel");
        this.state.select(id);
        this.insertWaypoint(id, this.eventWorld(ev));
      }
    });

    svg.addEventListener("contextmenu", (ev) => {
      if (ev.target.classList.contains("waypoint")) {
        ev.preventDefault();
        this.deleteWaypoint(ev.target.getAttribute("data-vessel"), Number(ev.target.getAttribute("data-index")));
      }
    });

    svg.addEventListener("keydown", (ev) => {
      // only a handle of the vessel selected now: the vessel of an earlier handle may be deselected or deleted
      if ((ev.key === "Delete" || ev.key === "Backspace") && this.activeWaypoint?.vessel === this.state.selected) {
        ev.preventDefault();
        this.deleteWaypoint(this.activeWaypoint.vessel, this.activeWaypoint.index);
      } else if (this.mode === "place" && (ev.key === "Enter" || ev.key === " ")) {
        // from the keyboard: the vessel goes where the cross in the map's middle is (the arrow keys move the map
        // under it); placing needed a pointer before (a review's)
        ev.preventDefault();
        ev.stopPropagation(); // the page's own Enter ends placing and drawing
        this.place(this.centre());
      } else if (this.mode === "draw" && ev.key === " ") {
        ev.preventDefault();
        ev.stopPropagation();
        this.appendWaypoint(this.centre());
      } else if (ev.key === "Enter" || ev.key === "Escape") {
        if (this.mode !== "select") this.setMode("select");
      } else if (ev.key.startsWith("Arrow") && !ev.ctrlKey && !ev.metaKey && !ev.altKey) {
        // the keyboard pans the map: an eighth of the view a press (Shift: half of it)
        ev.preventDefault();
        const { w, h } = this.size();
        const k = ev.shiftKey ? 0.5 : 0.125;
        const [dx, dy] = { ArrowLeft: [-w, 0], ArrowRight: [w, 0], ArrowUp: [0, h], ArrowDown: [0, -h] }[ev.key] || [0, 0];
        this.view = { ...this.view, cx: this.view.cx + (dx * k) / this.view.scale, cy: this.view.cy + (dy * k) / this.view.scale };
        this.applyView();
      } else if (["+", "=", "-", "_"].includes(ev.key) && !ev.ctrlKey && !ev.metaKey && !ev.altKey) {
        // and zooms about the middle, as the + and − buttons do
        ev.preventDefault();
        const { w, h } = this.size();
        this.zoomAt(ev.key === "+" || ev.key === "=" ? 1.5 : 1 / 1.5, w / 2, h / 2);
      }
    });
  }
}
