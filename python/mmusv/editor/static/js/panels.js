// The side panels: vessel library, fleet list, the selected vessel's form, the checks list and the scenario form
// (name, map, environment, acquisition, rigs). Every input writes into the document through state.edit, which
// re-evaluates it on the server; the forms are refilled from the document after every change.

const $ = (id) => document.getElementById(id);

function option(value, text = value) {
  const o = document.createElement("option");
  o.value = value;
  o.textContent = text;
  return o;
}

function fillSelect(select, values) {
  select.replaceChildren(...values.map((v) => (Array.isArray(v) ? option(v[0], v[1]) : option(v))));
}

function setValue(input, value) {
  if (document.activeElement === input) return; // do not fight the person typing
  input.value = value ?? "";
}

function numberOrNull(input) {
  if (input.value.trim() === "") return null;
  const n = Number(input.value);
  return Number.isFinite(n) ? n : input.value;
}

export class Panels {
  constructor(state, mapView) {
    this.state = state;
    this.map = mapView;
  }

  init(choices, assets) {
    const s = this.state;
    s.choices = choices;
    s.assets = assets;
    fillSelect($("v-role"), choices.role);
    fillSelect($("v-end"), choices.end.map((e) => [e, e.replace("_", " ")]));
    fillSelect($("v-asset"), assets.map((a) => [a.name, `${a.name} (${a.length} × ${a.beam} m)`]));
    fillSelect($("m-type"), choices.map_type.map((t) => [t, t.replace("_", " ")]));
    fillSelect($("e-weather"), choices.weather);
    fillSelect($("e-wave"), [...choices.wave.map((w) => [w.name, `${w.name} (H ${w.height_m} m)`]), ["custom", "custom height…"]]);
    this.renderLibrary();
    this.bindLibrary();
    this.bindVesselForm();
    this.bindScenarioForm();
  }

  // ------------------------------------------------------------------------------------- library

  renderLibrary() {
    const q = $("library-search").value.trim().toLowerCase();
    const ul = $("library");
    ul.replaceChildren();
    const armed = this.map.placing?.asset?.name;
    for (const a of this.state.assets) {
      const hay = `${a.name} ${a.category} ${a.class} ${a.description}`.toLowerCase();
      if (q && !q.split(/\s+/).every((w) => hay.includes(w))) continue;
      const li = document.createElement("li");
      li.dataset.asset = a.name;
      li.title = `${a.description}\n${a.length} m long, ${a.beam} m beam, ${a.height} m high, ${a.draft} m draft`;
      if (a.name === armed) li.classList.add("armed");
      const name = document.createElement("span");
      name.textContent = a.name;
      if (a.usv) {
        const tag = document.createElement("span");
        tag.className = "usv-tag";
        tag.textContent = "USV";
        name.appendChild(tag);
      }
      const size = document.createElement("span");
      size.className = "size";
      size.textContent = `${a.length} × ${a.beam} m`;
      li.append(name, size);
      ul.appendChild(li);
    }
  }

  bindLibrary() {
    $("library-search").addEventListener("input", () => this.renderLibrary());
    $("library").addEventListener("click", (ev) => {
      const li = ev.target.closest("li[data-asset]");
      if (!li) return;
      const asset = this.state.assets.find((a) => a.name === li.dataset.asset);
      if (this.map.mode === "place" && this.map.placing?.asset?.name === asset.name) {
        this.map.setMode("select");
      } else {
        this.map.setMode("place", { asset, role: $("library-role").value });
      }
      this.renderLibrary();
    });
    $("library-role").addEventListener("change", () => {
      if (this.map.mode === "place") this.map.setMode("place", { asset: this.map.placing.asset, role: $("library-role").value });
    });
  }

  // ------------------------------------------------------------------------------------- fleet and vessel

  renderFleet() {
    const ul = $("fleet");
    ul.replaceChildren();
    const vessels = this.state.doc?.vessels || [];
    $("vessel-count").textContent = String(vessels.length);
    const ev = this.state.evaluation;
    const sev = new Map();
    for (const p of ev?.problems || []) for (const id of p.vessels) if (sev.get(id) !== "error") sev.set(id, p.severity);
    for (const e of ev?.errors || []) if (e.vessel) sev.set(e.vessel, "error");
    for (const v of vessels) {
      const li = document.createElement("li");
      li.dataset.id = v.id;
      if (v.id === this.state.selected) li.classList.add("selected");
      const dot = document.createElement("span");
      dot.className = `dot ${v.role === "usv" ? "usv" : "target"}`;
      const id = document.createElement("span");
      id.textContent = v.id;
      li.append(dot, id);
      if (sev.has(v.id)) {
        const f = document.createElement("span");
        f.className = `flag ${sev.get(v.id)}`;
        f.textContent = "!";
        f.title = sev.get(v.id) === "error" ? "an error concerns this vessel" : "a check warns about this vessel";
        li.appendChild(f);
      }
      const asset = document.createElement("span");
      asset.className = "asset";
      asset.textContent = v.asset;
      li.appendChild(asset);
      ul.appendChild(li);
    }
  }

  renderVessel() {
    const v = this.state.vessel();
    $("vessel-panel").hidden = !v;
    if (!v) return;
    setValue($("v-id"), v.id);
    setValue($("v-role"), v.role || "target");
    setValue($("v-asset"), v.asset);
    const rigs = Object.keys(this.state.doc.rigs || {});
    fillSelect($("v-rig"), [["", "(default rig)"], ...rigs]);
    $("v-rig").value = v.rig || "";
    $("v-rig-label").hidden = v.role !== "usv";
    setValue($("v-speed"), v.speed_mps ?? 0);
    setValue($("v-end"), v.end || "stop");
    setValue($("v-offset"), v.start_offset_m ?? 0);
    const table = $("v-route");
    if (table.contains(document.activeElement)) return;
    table.replaceChildren();
    (v.route || []).forEach(([x, y], i) => {
      const tr = document.createElement("tr");
      tr.dataset.index = String(i);
      const idx = document.createElement("td");
      idx.className = "idx";
      idx.textContent = String(i);
      const cells = [x, y].map((val, j) => {
        const td = document.createElement("td");
        const input = document.createElement("input");
        input.type = "number";
        input.step = "1";
        input.value = String(val);
        input.dataset.axis = String(j);
        input.title = j === 0 ? "x east, metres" : "y north, metres";
        td.appendChild(input);
        return td;
      });
      const del = document.createElement("td");
      const b = document.createElement("button");
      b.textContent = "×";
      b.title = "delete this waypoint";
      b.dataset.delete = String(i);
      del.appendChild(b);
      tr.append(idx, ...cells, del);
      table.appendChild(tr);
    });
  }

  editVessel(fn) {
    const id = this.state.selected;
    const i = this.state.vesselIndex(id);
    if (i < 0) return;
    this.state.edit((doc) => fn(doc.vessels[i], doc));
  }

  bindVesselForm() {
    $("fleet").addEventListener("click", (ev) => {
      const li = ev.target.closest("li[data-id]");
      if (li) this.state.select(li.dataset.id);
    });
    $("fleet").addEventListener("dblclick", (ev) => {
      const li = ev.target.closest("li[data-id]");
      if (li) this.map.zoomTo(li.dataset.id);
    });
    $("v-id").addEventListener("change", (ev) => {
      const id = ev.target.value.trim();
      this.editVessel((v) => {
        v.id = id;
      });
      this.state.select(id);
    });
    $("v-role").addEventListener("change", (ev) => this.editVessel((v, doc) => {
      v.role = ev.target.value;
      if (v.role !== "usv") delete v.rig;
      else if (!v.rig && Object.keys(doc.rigs || {}).length) v.rig = Object.keys(doc.rigs)[0];
    }));
    $("v-asset").addEventListener("change", (ev) => this.editVessel((v) => {
      v.asset = ev.target.value;
    }));
    $("v-rig").addEventListener("change", (ev) => this.editVessel((v) => {
      if (ev.target.value) v.rig = ev.target.value;
      else delete v.rig;
    }));
    $("v-speed").addEventListener("change", (ev) => this.editVessel((v) => {
      v.speed_mps = numberOrNull(ev.target) ?? 0;
    }));
    $("v-end").addEventListener("change", (ev) => this.editVessel((v) => {
      if (ev.target.value === "stop") delete v.end;
      else v.end = ev.target.value;
    }));
    $("v-offset").addEventListener("change", (ev) => this.editVessel((v) => {
      const n = numberOrNull(ev.target);
      if (n === null || n === 0) delete v.start_offset_m;
      else v.start_offset_m = n;
    }));
    $("v-route").addEventListener("change", (ev) => {
      const input = ev.target;
      const row = input.closest("tr");
      if (!row || input.dataset.axis === undefined) return;
      const i = Number(row.dataset.index), j = Number(input.dataset.axis);
      this.editVessel((v) => {
        v.route[i][j] = numberOrNull(input) ?? 0;
      });
    });
    $("v-route").addEventListener("click", (ev) => {
      const b = ev.target.closest("button[data-delete]");
      if (b) this.map.deleteWaypoint(this.state.selected, Number(b.dataset.delete));
    });
    $("v-extend").addEventListener("click", () => {
      if (this.state.selected) this.map.setMode("draw", { vessel: this.state.selected });
    });
    $("v-zoom").addEventListener("click", () => this.map.zoomTo(this.state.selected));
    $("v-delete").addEventListener("click", () => {
      const id = this.state.selected;
      this.state.edit((doc) => {
        doc.vessels = doc.vessels.filter((v) => v.id !== id);
      });
      this.state.select(null);
    });
  }

  // ------------------------------------------------------------------------------------- checks list

  renderProblems() {
    const ul = $("problems");
    ul.replaceChildren();
    const ev = this.state.evaluation;
    const count = $("problem-count");
    if (!ev) {
      count.textContent = "…";
      const li = document.createElement("li");
      li.className = "ok";
      li.textContent = this.state.evalError ? `cannot check: ${this.state.evalError}` : "checking…";
      ul.appendChild(li);
      return;
    }
    const items = [
      ...ev.errors.map((e) => ({ severity: "error", check: "schema", field: e.field, message: e.message, vessels: e.vessel ? [e.vessel] : [], point: null })),
      ...ev.problems,
    ];
    count.textContent = String(items.length);
    if (!items.length) {
      const li = document.createElement("li");
      li.className = "ok";
      li.textContent = "All checks pass: the routes stay on navigable water with clearance, vessels keep apart, every target is in LiDAR range and sight of a USV, the USVs cooperate.";
      ul.appendChild(li);
      return;
    }
    for (const p of items) {
      const li = document.createElement("li");
      li.className = `problem ${p.severity}`;
      li.dataset.check = p.check;
      li.dataset.field = p.field || "";
      li.dataset.vessels = (p.vessels || []).join(",");
      const check = document.createElement("span");
      check.className = "check";
      check.textContent = `${p.severity === "error" ? "error" : "warning"} · ${p.check}`;
      const field = document.createElement("span");
      field.className = "field";
      field.textContent = p.field ? `  ${p.field}` : "";
      const msg = document.createElement("span");
      msg.className = "msg";
      msg.textContent = p.message;
      li.append(check, field, msg);
      li.addEventListener("click", () => {
        if (p.vessels?.length) this.state.select(p.vessels[0]);
        if (p.point) {
          this.map.view = { ...this.map.view, cx: p.point[0], cy: p.point[1], scale: Math.max(this.map.view.scale, 1) };
          this.map.applyView();
        } else if (p.vessels?.length) {
          this.map.zoomTo(p.vessels[0]);
        }
      });
      ul.appendChild(li);
    }
  }

  // ------------------------------------------------------------------------------------- scenario form

  renderScenario() {
    const d = this.state.doc;
    if (!d) return;
    setValue($("s-name"), d.name);
    setValue($("s-seed"), d.seed ?? 0);
    setValue($("s-comment"), this.state.comment);
    setValue($("m-type"), d.map?.type || "island");
    setValue($("m-seed"), d.map?.seed ?? 0);
    setValue($("m-params"), d.map?.params ? JSON.stringify(d.map.params) : "");
    const env = d.environment || {};
    setValue($("e-time"), env.time_of_day || "12:00");
    setValue($("e-weather"), env.weather || "clear");
    const presets = this.state.choices.wave.map((w) => w.name);
    const wave = env.wave ?? "W0";
    setValue($("e-wave"), typeof wave === "string" && presets.includes(wave) ? wave : "custom");
    setValue($("e-visibility"), env.visibility_m);
    setValue($("e-rain"), env.rain_mm_per_h);
    const acq = d.acquisition || {};
    setValue($("a-frequency"), acq.frequency_hz ?? 5);
    setValue($("a-frames"), acq.frames ?? 100);
    this.renderRigs();
  }

  renderRigs() {
    const box = $("rigs");
    if (box.contains(document.activeElement)) return;
    box.replaceChildren();
    const rigs = this.state.doc.rigs || {};
    for (const [name, rig] of Object.entries(rigs)) {
      const div = document.createElement("div");
      div.className = "rig";
      div.dataset.rig = name;
      const head = document.createElement("div");
      head.className = "rig-head";
      head.textContent = name;
      const del = document.createElement("button");
      del.textContent = "Remove";
      del.dataset.action = "remove";
      head.appendChild(del);
      const grid = document.createElement("div");
      grid.className = "grid";
      const lidar = rig.lidar === null ? null : rig.lidar || {};
      const radarOn = rig.radar === undefined ? (rig.preset || "full") === "full" : rig.radar !== null;
      const fields = [
        ["preset", "select", rig.preset || "full", this.state.choices.rig_preset],
        ["LiDAR channels", "number", lidar?.channels ?? "", null, "default"],
        ["LiDAR range m", "number", lidar?.range_m ?? "", null, "default"],
        ["radar", "select", radarOn ? "on" : "off", ["on", "off"]],
        ["camera quality", "select", rig.quality || "default", ["default", ...this.state.choices.camera_quality]],
      ];
      const keys = ["preset", "lidar.channels", "lidar.range_m", "radar", "quality"];
      fields.forEach(([label, kind, value, options, placeholder], i) => {
        const l = document.createElement("label");
        l.textContent = label;
        let input;
        if (kind === "select") {
          input = document.createElement("select");
          fillSelect(input, options);
        } else {
          input = document.createElement("input");
          input.type = "number";
          input.min = "1";
          if (placeholder) input.placeholder = placeholder;
        }
        input.value = String(value);
        input.dataset.key = keys[i];
        l.appendChild(input);
        grid.appendChild(l);
      });
      const summary = document.createElement("div");
      summary.className = "summary";
      const users = (this.state.doc.vessels || []).filter((v) => v.rig === name).map((v) => v.id);
      const cams = Array.isArray(rig.cameras) ? `${rig.cameras.length} cameras` : (rig.preset || "full") === "full" ? "4 surround cameras" : "no cameras";
      summary.textContent = `${cams}; carried by ${users.length ? users.join(", ") : "no vessel"}. Other sensor settings: edit the YAML.`;
      div.append(head, grid, summary);
      box.appendChild(div);
    }
  }

  editRig(name, key, input) {
    this.state.edit((doc) => {
      const rig = doc.rigs[name];
      if (key === "preset") {
        if (input.value === "full") delete rig.preset;
        else rig.preset = input.value;
      } else if (key === "quality") {
        // every camera and top view of the rig that does not set its own (default: each camera's, standard)
        if (input.value === "default") delete rig.quality;
        else rig.quality = input.value;
      } else if (key === "radar") {
        const full = (rig.preset || "full") === "full";
        if (input.value === "off") {
          if (full) rig.radar = null;
          else delete rig.radar;
        } else if (full) delete rig.radar;
        else rig.radar = {};
      } else {
        const [part, field] = key.split(".");
        const n = numberOrNull(input);
        if (rig[part] === null) rig[part] = {};
        rig[part] ||= {};
        if (n === null) delete rig[part][field];
        else rig[part][field] = n;
        if (!Object.keys(rig[part]).length) delete rig[part];
      }
    });
  }

  bindScenarioForm() {
    const edit = (fn) => this.state.edit(fn);
    $("s-name").addEventListener("change", (ev) => edit((d) => {
      d.name = ev.target.value.trim();
    }));
    $("s-seed").addEventListener("change", (ev) => edit((d) => {
      d.seed = numberOrNull(ev.target) ?? 0;
    }));
    $("s-comment").addEventListener("change", (ev) => {
      this.state.comment = ev.target.value;
      this.state.dirty = true;
      this.state.emit("doc");
    });
    $("m-type").addEventListener("change", (ev) => edit((d) => {
      d.map = { ...d.map, type: ev.target.value };
      delete d.map.params; // parameters belong to one map type
    }));
    $("m-seed").addEventListener("change", (ev) => edit((d) => {
      d.map = { ...d.map, seed: numberOrNull(ev.target) ?? 0 };
    }));
    $("m-params").addEventListener("change", (ev) => {
      const text = ev.target.value.trim();
      let params;
      try {
        params = text ? JSON.parse(text) : null;
      } catch (err) {
        this.state.emit("status", { text: `map parameters: not JSON (${err.message})`, error: true });
        return;
      }
      edit((d) => {
        if (params === null || (typeof params === "object" && !Object.keys(params).length)) delete d.map.params;
        else d.map.params = params;
      });
    });
    const env = (key, value) => edit((d) => {
      d.environment ||= {};
      if (value === null || value === "") delete d.environment[key];
      else d.environment[key] = value;
    });
    $("e-time").addEventListener("change", (ev) => env("time_of_day", ev.target.value));
    $("e-weather").addEventListener("change", (ev) => env("weather", ev.target.value));
    $("e-wave").addEventListener("change", (ev) => {
      if (ev.target.value !== "custom") return env("wave", ev.target.value);
      const h = window.prompt("Wave height in metres", "1.0");
      if (h !== null && h.trim() !== "") env("wave", Number(h));
      else this.renderScenario();
    });
    $("e-visibility").addEventListener("change", (ev) => env("visibility_m", numberOrNull(ev.target)));
    $("e-rain").addEventListener("change", (ev) => env("rain_mm_per_h", numberOrNull(ev.target)));
    const acq = (key, input) => edit((d) => {
      d.acquisition ||= {};
      const n = numberOrNull(input);
      if (n === null) delete d.acquisition[key];
      else d.acquisition[key] = n;
    });
    $("a-frequency").addEventListener("change", (ev) => acq("frequency_hz", ev.target));
    $("a-frames").addEventListener("change", (ev) => acq("frames", ev.target));
    $("rigs").addEventListener("change", (ev) => {
      const key = ev.target.dataset.key;
      const rig = ev.target.closest("[data-rig]")?.dataset.rig;
      if (key && rig) this.editRig(rig, key, ev.target);
    });
    $("rigs").addEventListener("click", (ev) => {
      const b = ev.target.closest("button[data-action=remove]");
      if (!b) return;
      const name = b.closest("[data-rig]").dataset.rig;
      edit((d) => {
        delete d.rigs[name];
        for (const v of d.vessels || []) if (v.rig === name) delete v.rig;
      });
    });
    $("rig-add").addEventListener("click", () => {
      const name = $("rig-new-name").value.trim() || `rig_${Object.keys(this.state.doc.rigs || {}).length + 1}`;
      edit((d) => {
        d.rigs ||= {};
        if (!(name in d.rigs)) d.rigs[name] = {};
      });
      $("rig-new-name").value = "";
    });
  }
}
