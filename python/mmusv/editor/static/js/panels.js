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
  // an entry the page refused stays as typed, beside its note, until the person changes it
  if (input.tagName === "INPUT" && input.dataset.refused === "1") return;
  input.value = value ?? "";
}

/** Shows `value` in `select`, with an option of its own saying `why` (as "tugg (not in the library)") when none of
 * the menu's options is it: a scenario naming an asset or rig that is not there showed a blank menu. That option goes
 * again once the value is one of the menu's. */
function selectValue(select, value, why) {
  for (const o of select.querySelectorAll("option[data-missing]")) o.remove();
  const v = value ?? "";
  if (![...select.options].some((o) => o.value === v)) {
    const o = option(v, `${v} (${why})`);
    o.dataset.missing = "1";
    select.appendChild(o);
  }
  select.value = v;
}

/** Shows `value` in `select` as selectValue does (an option of its own, "snow (not a weather)", where the menu has
 * no such value: a value the schema refuses, in a file opened to be fixed, showed a blank menu beside its note), but
 * not while the person is in it. */
function showChoice(select, value, why) {
  if (document.activeElement === select) return;
  selectValue(select, String(value), why);
}

function numberOrNull(input) {
  if (input.value.trim() === "") return null;
  const n = Number(input.value);
  return Number.isFinite(n) ? n : input.value;
}

/** Enter or Space on an item matching `selector` inside `list` clicks it (items that act on a click are buttons to
 * a keyboard too). */
function clickOnEnter(list, selector) {
  list.addEventListener("keydown", (ev) => {
    const item = ev.target.closest(selector);
    if (!item || ev.target !== item || (ev.key !== "Enter" && ev.key !== " ")) return;
    ev.preventDefault();
    ev.stopPropagation(); // not also the page's Enter (which ends placing and drawing)
    item.click();
  });
}

/** The form fields that can carry a note (the Checks list's items have a data-field too). */
const FIELDS = ["input", "select", "textarea", "table"].map((t) => `#left ${t}[data-field], #right ${t}[data-field]`).join(", ");

const RIG_NAME = /^[A-Za-z0-9_-]{1,64}$/;

function isMapping(value) {
  return value !== null && typeof value === "object" && !Array.isArray(value);
}

/** The key path (`state`, `quays.0`) of the first number in the parsed JSON `value` that is not finite, or null:
 * JSON.parse reads 1e999 as Infinity, which JSON.stringify then sends as null (a sea state of 1e999 became "no
 * state" without a word). */
function nonFinite(value, path = "") {
  if (typeof value === "number") return Number.isFinite(value) ? null : path;
  if (value === null || typeof value !== "object") return null;
  for (const [key, item] of Object.entries(value)) {
    const found = nonFinite(item, path ? `${path}.${key}` : key);
    if (found !== null) return found;
  }
  return null;
}

/** A time of day as an <input type="time"> shows it ("HH:MM"): "6:05" and " 06:05 ", which the schema takes too,
 * become "06:05"; anything else is left as it is (the box then shows it empty, beside the schema's note). */
function hhmm(text) {
  const m = typeof text === "string" ? /^\s*([0-9]{1,2}):([0-9]{2})\s*$/.exec(text) : null;
  return m ? `${m[1].padStart(2, "0")}:${m[2]}` : text;
}

/** Whether the scenario's schema error at `field` (its message `message`) concerns the form field `path`: the same
 * field or one inside it, or a check across a section's fields (`environment`) that names this field's key. */
function concerns(field, message, path) {
  if (!field) return false;
  if (field === path || field.startsWith(`${path}.`) || field.startsWith(`${path}[`)) return true;
  const key = path.slice(path.lastIndexOf(".") + 1);
  return path.startsWith(`${field}.`) && /^[a-z_]+$/.test(key) && message.includes(key);
}

export class Panels {
  constructor(state, mapView) {
    this.state = state;
    this.map = mapView;
    // Entries the page did not write into the scenario (a number box the browser cannot read, an id another
    // vessel has, map parameters that are not JSON): field path -> the note shown next to the field. The scenario
    // keeps its value, every other edit stays; the note goes when the field is changed again or the scenario is
    // replaced (open, undo, redo).
    this.refused = new Map();
    this.lastErrors = [];
    this.libraryStop = null; // the library entry that holds its one tab stop (renderLibrary)
    this.assetsKey = null; // the `assets:` entries of the scenario whose library is shown (setAssets)
    // The wave a scenario had when a sea was typed over it: clearing the sea brings it back (none: the default W0).
    this.waveBeforeSea = undefined;
    state.on("jump", () => {
      this.forgetRefused("");
      this.waveBeforeSea = undefined; // another scenario, or another version of it
    });
    // A number box refused as empty, then given another text the browser cannot read ("1e400" after "NaN"): its
    // value stays "", so no change event comes and the note kept saying "empty" (a review's). On leaving the box
    // the note says what is there now.
    document.addEventListener("focusout", (ev) => {
      const el = ev.target;
      if (!(el instanceof HTMLInputElement) || el.type !== "number" || !el.validity.badInput) return;
      const text = el.dataset.field ? this.refused.get(el.dataset.field) : undefined;
      if (text && text.includes(": empty; ")) this.refuse(el, text.replace(": empty; ", ": not a number; "));
    });
  }

  // ------------------------------------------------------------------------------------- notes next to fields

  /** Refuses what was typed into `input` (its `data-field` path): the scenario is left as it is, `message` says
   * why and what is allowed, next to the field. */
  refuse(input, message) {
    this.refused.set(input.dataset.field, message);
    if (input.tagName === "INPUT") input.dataset.refused = "1";
    this.renderNotes();
  }

  /** Clears the refusal of `input`'s field (it was changed again and is being applied). */
  accept(input) {
    this.refused.delete(input.dataset.field);
    delete input.dataset.refused;
  }

  /** Forgets the refusals of the fields under `prefix` ("" for all), and shows the scenario's values there again. */
  forgetRefused(prefix) {
    for (const key of [...this.refused.keys()]) if (key.startsWith(prefix)) this.refused.delete(key);
    for (const input of document.querySelectorAll("[data-refused]")) {
      if (input.dataset.field.startsWith(prefix)) delete input.dataset.refused;
    }
  }

  /** A number typed into `input`, null when it is empty; undefined when the browser cannot read it as a number
   * ("1e", "1e400", "--1"), which is refused with a note saying what `allowed`. With `required`, empty is refused
   * too. */
  readNumber(input, label, allowed, { required = false } = {}) {
    if (input.validity?.badInput || (required && input.value.trim() === "")) {
      const what = input.validity?.badInput ? "not a number" : "empty";
      this.refuse(input, `${label}: ${what}; type ${allowed}. The scenario keeps its value.`);
      return undefined;
    }
    this.accept(input);
    return numberOrNull(input);
  }

  /** Shows next to every form field the refusal of what was typed there, or the scenario's schema error about it
   * (from the last check: the Checks list has them all), and marks the field invalid for assistive technology. */
  renderNotes() {
    const ev = this.state.evaluation;
    if (ev) this.lastErrors = ev.errors || [];
    else if (this.state.evalError) this.lastErrors = [];
    let n = 0;
    for (const el of document.querySelectorAll(FIELDS)) {
      const path = el.dataset.field;
      let text = this.refused.get(path) || null;
      if (!text) {
        const errs = this.lastErrors.filter((e) => concerns(e.field, e.message, path));
        if (errs.length) text = errs.map((e) => e.message).join("; ");
      }
      let note = el.nextElementSibling?.classList.contains("field-note") ? el.nextElementSibling : null;
      if (!text) {
        note?.remove();
        el.removeAttribute("aria-invalid");
        if (el.getAttribute("aria-describedby")?.startsWith("note-")) el.removeAttribute("aria-describedby");
        continue;
      }
      if (!note) {
        note = document.createElement("span");
        note.className = "field-note";
        el.insertAdjacentElement("afterend", note);
      }
      note.id = `note-${++n}`;
      note.dataset.for = path;
      note.textContent = text;
      el.setAttribute("aria-invalid", "true");
      el.setAttribute("aria-describedby", note.id);
    }
  }

  init(choices, assets, key) {
    const s = this.state;
    s.choices = choices;
    this.setAssets(assets, key);
    fillSelect($("v-role"), choices.role);
    fillSelect($("v-end"), choices.end.map((e) => [e, e.replace("_", " ")]));
    fillSelect($("m-type"), choices.map_type.map((t) => [t, t.replace("_", " ")]));
    fillSelect($("e-weather"), choices.weather);
    fillSelect($("e-wave"), [...choices.wave.map((w) => [w.name, `${w.name} (H ${w.height_m} m)`]), ["custom", "custom height…"], ["sea", "by the sea"]]);
    fillSelect($("e-motion"), choices.motion);
    [$("e-wave-height").min, $("e-wave-height").max] = this.waveRange().map(String);
    this.renderLibrary();
    this.bindLibrary();
    clickOnEnter($("problems"), "li.problem");
    this.bindVesselForm();
    this.bindScenarioForm();
  }

  // ------------------------------------------------------------------------------------- library

  /** Shows `assets` (the library of the scenario whose `assets:` entries `key` names: the built-in assets and its own
   * asset files') in the library and the selected vessel's asset menu. A vessel being placed is placed as the
   * library's asset of that name now, or no longer when it has none. */
  setAssets(assets, key) {
    this.state.assets = assets;
    this.assetsKey = key;
    const menu = $("v-asset");
    const was = menu.value;
    fillSelect(menu, assets.map((a) => [a.name, `${a.name} (${a.length} × ${a.beam} m)`]));
    menu.value = was; // the vessel form (renderVessel) says so when this library lacks it
    if (this.map.mode === "place") {
      const asset = assets.find((a) => a.name === this.map.placing?.asset?.name);
      if (asset) this.map.setMode("place", { ...this.map.placing, asset });
      else this.map.setMode("select");
    }
    this.renderLibrary();
  }

  renderLibrary() {
    const q = $("library-search").value.trim().toLowerCase();
    const ul = $("library");
    const focused = document.activeElement?.closest?.("#library li")?.dataset.asset;
    ul.replaceChildren();
    const armed = this.map.placing?.asset?.name;
    // One tab stop for the whole list (a roving tabindex, as WAI-ARIA's listbox and toolbar patterns): the entry
    // focused last, else the armed one, else the first; the arrow keys, Home and End move among the entries.
    const stop = focused ?? this.libraryStop ?? armed;
    for (const a of this.state.assets) {
      const hay = `${a.name} ${a.category} ${a.class} ${a.description}`.toLowerCase();
      if (q && !q.split(/\s+/).every((w) => hay.includes(w))) continue;
      const li = document.createElement("li");
      li.dataset.asset = a.name;
      li.tabIndex = -1;
      li.setAttribute("role", "button");
      li.setAttribute("aria-pressed", String(a.name === armed));
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
      if (a.name === focused) li.focus();
    }
    const entries = [...ul.children];
    (entries.find((li) => li.dataset.asset === stop) ?? entries[0])?.setAttribute("tabindex", "0");
  }

  /** Moves the library's one tab stop to ``li`` and focuses it. */
  focusLibraryEntry(li) {
    for (const other of $("library").querySelectorAll('li[tabindex="0"]')) other.tabIndex = -1;
    li.tabIndex = 0;
    this.libraryStop = li.dataset.asset;
    li.focus();
    li.scrollIntoView({ block: "nearest" });
  }

  bindLibrary() {
    $("library-search").addEventListener("input", () => this.renderLibrary());
    clickOnEnter($("library"), "li[data-asset]");
    $("library").addEventListener("keydown", (ev) => {
      const li = ev.target.closest("li[data-asset]");
      if (!li || ev.ctrlKey || ev.metaKey || ev.altKey) return;
      const entries = [...$("library").children];
      const at = entries.indexOf(li);
      const to = { ArrowDown: at + 1, ArrowUp: at - 1, Home: 0, End: entries.length - 1 }[ev.key];
      if (to === undefined) return;
      ev.preventDefault();
      if (to >= 0 && to < entries.length) this.focusLibraryEntry(entries[to]);
    });
    $("library").addEventListener("focusin", (ev) => {
      const li = ev.target.closest("li[data-asset]");
      if (li && li.tabIndex !== 0) this.focusLibraryEntry(li); // reached by a click: the tab stop follows
    });
    $("library-search").addEventListener("keydown", (ev) => {
      // from the search box down into what it found
      const first = $("library").querySelector("li[data-asset]");
      if (ev.key === "ArrowDown" && first) {
        ev.preventDefault();
        this.focusLibraryEntry(first);
      }
    });
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
      $("library").querySelector(`li[data-asset="${CSS.escape(asset.name)}"]`)?.focus();
    });
    $("library-role").addEventListener("change", () => {
      if (this.map.mode === "place") this.map.setMode("place", { asset: this.map.placing.asset, role: $("library-role").value });
    });
  }

  // ------------------------------------------------------------------------------------- fleet and vessel

  renderFleet() {
    const ul = $("fleet");
    const focused = document.activeElement?.closest?.("#fleet li")?.dataset.id;
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
      li.tabIndex = 0;
      li.setAttribute("role", "button");
      li.setAttribute("aria-pressed", String(v.id === this.state.selected));
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
      if (v.id === focused) li.focus();
    }
  }

  renderVessel() {
    const v = this.state.vessel();
    $("vessel-panel").hidden = !v;
    if ((v?.id ?? null) !== this.shownVessel) {
      this.forgetRefused("vessels["); // another vessel: its own values, and an empty row to add a waypoint
      $("v-add-x").value = $("v-add-y").value = "";
    }
    this.shownVessel = v?.id ?? null;
    if (!v) return;
    const at = `vessels[${this.state.vesselIndex(v.id)}]`;
    const keys = { "v-id": "id", "v-role": "role", "v-asset": "asset", "v-rig": "rig", "v-speed": "speed_mps", "v-end": "end", "v-offset": "start_offset_m" };
    for (const [id, key] of Object.entries(keys)) $(id).dataset.field = `${at}.${key}`;
    $("v-route").dataset.field = `${at}.route`;
    $("v-add-x").dataset.field = `${at}.route.(new)[0]`;
    $("v-add-y").dataset.field = `${at}.route.(new)[1]`;
    setValue($("v-id"), v.id);
    setValue($("v-role"), v.role || "target");
    selectValue($("v-asset"), v.asset, "not in the library");
    const rigs = Object.keys(this.state.doc.rigs || {});
    fillSelect($("v-rig"), [["", "(default rig)"], ...rigs]);
    selectValue($("v-rig"), v.rig || "", "no such rig");
    $("v-rig-label").hidden = v.role !== "usv";
    setValue($("v-speed"), v.speed_mps ?? 0);
    setValue($("v-end"), v.end || "stop");
    setValue($("v-offset"), v.start_offset_m ?? 0);
    const table = $("v-route-rows");
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
        input.dataset.field = `${at}.route[${i}][${j}]`;
        const refused = this.refused.get(input.dataset.field);
        if (refused) input.dataset.refused = "1";
        input.title = j === 0 ? "x east, metres" : "y north, metres";
        input.setAttribute("aria-label", `waypoint ${i} ${j === 0 ? "x east" : "y north"}, metres`);
        td.appendChild(input);
        return td;
      });
      const del = document.createElement("td");
      const b = document.createElement("button");
      b.textContent = "×";
      b.title = "delete this waypoint";
      b.setAttribute("aria-label", `delete waypoint ${i}`);
      b.dataset.delete = String(i);
      del.appendChild(b);
      tr.append(idx, ...cells, del);
      table.appendChild(tr);
    });
  }

  /** Adds the waypoint typed into the route's last row at the end of the selected vessel's route; an empty or
   * unreadable x or y is refused next to its box (the route stays as it was). */
  addWaypoint() {
    const [bx, by] = [$("v-add-x"), $("v-add-y")];
    const allowed = "a position in metres";
    const x = this.readNumber(bx, "new waypoint x (east)", allowed, { required: true });
    const y = this.readNumber(by, "new waypoint y (north)", allowed, { required: true });
    if (x === undefined || y === undefined) {
      (x === undefined ? bx : by).focus();
      return;
    }
    this.renderNotes();
    this.editVessel((v) => {
      v.route ||= [];
      v.route.push([x, y]);
    });
    bx.value = by.value = "";
    bx.focus(); // ready for the next one
  }

  editVessel(fn) {
    const id = this.state.selected;
    const i = this.state.vesselIndex(id);
    if (i < 0) return;
    this.state.edit((doc) => fn(doc.vessels[i], doc));
  }

  bindVesselForm() {
    clickOnEnter($("fleet"), "li[data-id]");
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
      const others = (this.state.doc.vessels || []).filter((v) => v.id !== this.state.selected).map((v) => v.id);
      if (!id) {
        // written, the vessel would have no name in the list or on the map, and the buttons that act on the
        // selected vessel (Extend route, Zoom to) would find none
        this.refuse(ev.target, `id: empty; give the vessel an id (e.g. usv_1, tanker). It keeps ${JSON.stringify(this.state.selected)}.`);
        return;
      }
      if (others.includes(id)) {
        // written, the panel would show the other vessel of that id and the next edit would go to it
        this.refuse(ev.target, `id: ${JSON.stringify(id)} is the id of another vessel; give this vessel an id of its own (ids must be unique). It keeps ${JSON.stringify(this.state.selected)}.`);
        return;
      }
      this.accept(ev.target);
      this.state.renameVessel(this.state.selected, id);
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
    $("v-speed").addEventListener("change", (ev) => {
      const n = this.readNumber(ev.target, "speed", "a speed in m/s, 0 or more", { required: true });
      if (n !== undefined) this.editVessel((v) => {
        v.speed_mps = n;
      });
    });
    $("v-end").addEventListener("change", (ev) => this.editVessel((v) => {
      if (ev.target.value === "stop") delete v.end;
      else v.end = ev.target.value;
    }));
    $("v-offset").addEventListener("change", (ev) => {
      const n = this.readNumber(ev.target, "start offset", "metres along the route, 0 or more (empty: 0)");
      if (n !== undefined) this.editVessel((v) => {
        if (n === null || n === 0) delete v.start_offset_m;
        else v.start_offset_m = n;
      });
    });
    $("v-route").addEventListener("change", (ev) => {
      const input = ev.target;
      const row = input.closest("tr");
      if (!row || input.dataset.axis === undefined) return;
      const i = Number(row.dataset.index), j = Number(input.dataset.axis);
      const axis = j === 0 ? "x (east)" : "y (north)";
      const n = this.readNumber(input, `waypoint ${i} ${axis}`, "a position in metres", { required: true });
      if (n !== undefined) this.editVessel((v) => {
        v.route[i][j] = n;
      });
    });
    $("v-route").addEventListener("click", (ev) => {
      const b = ev.target.closest("button[data-delete]");
      if (b) this.map.deleteWaypoint(this.state.selected, Number(b.dataset.delete));
    });
    // the route's last row adds a waypoint from the keyboard: x and y, then Enter (or its + button)
    for (const [id, axis] of [["v-add-x", "x (east)"], ["v-add-y", "y (north)"]]) {
      $(id).addEventListener("blur", (ev) => {
        // what the browser cannot read is refused on leaving the box (a change event does not come: the value of
        // "1e" is "", as it was); an empty box is refused only when adding, a number takes the note away
        const box = ev.target;
        if (box.validity.badInput) this.readNumber(box, `new waypoint ${axis}`, "a position in metres");
        else if (box.value.trim() !== "" && this.refused.has(box.dataset.field)) {
          this.accept(box);
          this.renderNotes();
        }
      });
      $(id).addEventListener("keydown", (ev) => {
        if (ev.key !== "Enter") return;
        ev.preventDefault();
        ev.stopPropagation();
        this.addWaypoint();
      });
    }
    $("v-add-waypoint").addEventListener("click", () => this.addWaypoint());
    $("v-extend").addEventListener("click", () => {
      if (this.state.selected) this.map.setMode("draw", { vessel: this.state.selected });
    });
    $("v-zoom").addEventListener("click", () => this.map.zoomTo(this.state.selected));
    $("v-delete").addEventListener("click", () => {
      const id = this.state.selected;
      const at = this.state.vesselIndex(id);
      this.forgetRefused("vessels[");
      this.state.edit((doc) => {
        doc.vessels = doc.vessels.filter((v) => v.id !== id);
      });
      this.state.select(null);
      // the button is gone with the vessel's panel: the keyboard goes on at the vessel that took its place in the
      // list (else the last one, else the library), not at the top of the page
      const items = $("fleet").querySelectorAll("li[data-id]");
      (items[Math.min(at, items.length - 1)] || $("library-search")).focus();
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
      // a schema error goes to the form field it concerns (a vessel's, once the vessel is selected)
      const schemaField = p.check === "schema" && p.field;
      if (p.vessels?.length || p.point || (schemaField && this.fieldFor(p))) {
        li.tabIndex = 0; // Enter shows it, like a click
        li.setAttribute("role", "button");
        li.title = schemaField ? "show the field" : "show it on the map";
      }
      li.addEventListener("click", () => {
        if (p.vessels?.length) this.state.select(p.vessels[0]);
        if (p.point) {
          this.map.view = { ...this.map.view, cx: p.point[0], cy: p.point[1], scale: Math.max(this.map.view.scale, 1) };
          this.map.applyView();
        } else if (p.vessels?.length) {
          this.map.zoomTo(p.vessels[0]);
        }
        if (schemaField) {
          const el = this.fieldFor(p);
          if (el) {
            el.scrollIntoView({ block: "center" });
            el.focus({ preventScroll: true });
          }
        }
      });
      ul.appendChild(li);
    }
  }

  /** The form field, shown on the page, that the schema error `p` concerns (for a table, its first box), or null. */
  fieldFor(p) {
    for (const el of document.querySelectorAll(FIELDS)) {
      if (el.closest("[hidden]") || !concerns(p.field, p.message, el.dataset.field)) continue;
      const box = el.tagName === "TABLE" ? el.querySelector("input, button") : el;
      if (box) return box;
    }
    return null;
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
    // the time box shows "HH:MM" only: a time the schema takes as "6:05" or " 06:05" is shown as 06:05
    setValue($("e-time"), hhmm(env.time_of_day || "12:00"));
    showChoice($("e-weather"), env.weather || "clear", "not a weather");
    const wave = this.waveChoice();
    setValue($("e-wave"), wave);
    // a custom wave's height has its own box; one field at a time carries the wave's notes: the box while the wave
    // is custom, the select otherwise
    const custom = wave === "custom";
    $("e-wave-height-label").hidden = !custom;
    for (const [el, on] of [[$("e-wave"), !custom], [$("e-wave-height"), custom]]) {
      if (on) {
        el.dataset.field = "environment.wave";
      } else if (el.dataset.field !== undefined) {
        el.removeAttribute("data-field"); // and its note and refusal, which the notes no longer see
        delete el.dataset.refused;
        if (el.nextElementSibling?.classList.contains("field-note")) el.nextElementSibling.remove();
        el.removeAttribute("aria-invalid");
        el.removeAttribute("aria-describedby");
      }
    }
    if (custom) setValue($("e-wave-height"), env.wave);
    showChoice($("e-motion"), env.motion || "physical", "not a motion");
    setValue($("e-sea"), env.sea == null ? "" : JSON.stringify(env.sea));
    setValue($("e-visibility"), env.visibility_m);
    setValue($("e-rain"), env.rain_mm_per_h);
    setValue($("e-latitude"), env.latitude_deg);
    setValue($("e-day"), env.day_of_year);
    const acq = d.acquisition || {};
    setValue($("a-frequency"), acq.frequency_hz ?? 5);
    setValue($("a-frames"), acq.frames ?? 100);
    this.renderRigs();
  }

  /** The wave heights a scenario may give, metres: [lowest, highest] (the schema's bounds, from the server). */
  waveRange() {
    return this.state.choices.wave_height_m || [0, 25];
  }

  /** The wave select's value for the scenario's wave (a preset's name, or "custom" for a height, whose option then
   * shows it). */
  waveChoice() {
    const presets = this.state.choices.wave.map((w) => w.name);
    const env = this.state.doc.environment || {};
    // a preset as the schema reads it: " w2" is W2 (a file that does not validate comes to the page as written, and
    // its W2 showed as "custom height…" beside an empty box)
    const wave = typeof env.wave === "string" ? env.wave.trim().toUpperCase() : env.wave ?? "W0";
    const custom = $("e-wave").querySelector('option[value="custom"]');
    custom.textContent = typeof wave === "number" ? `custom: H ${wave} m` : "custom height…";
    // a `sea` with the default wave: the sea sets the waves, not W0 (the select says so; picking a wave replaces it)
    const bySea = isMapping(env.sea) && wave === "W0";
    const sea = $("e-wave").querySelector('option[value="sea"]');
    sea.hidden = sea.disabled = !bySea;
    if (bySea) return "sea";
    return typeof wave === "string" && presets.includes(wave) ? wave : "custom";
  }

  /** What the rig panel shows of rig `name`: each field's [label, kind, value, options, placeholder] by its key, and
   * the summary line. */
  rigView(name, rig) {
    const lidar = rig.lidar === null ? null : rig.lidar || {};
    const radarOn = rig.radar === undefined ? (rig.preset || "full") === "full" : rig.radar !== null;
    // [label, kind, value, options, placeholder of a box or what a select says of a value it does not offer]
    const fields = {
      preset: ["preset", "select", rig.preset || "full", this.state.choices.rig_preset, "not a rig preset"],
      "lidar.channels": ["LiDAR channels", "number", lidar?.channels ?? "", null, "default"],
      "lidar.range_m": ["LiDAR range m", "number", lidar?.range_m ?? "", null, "default"],
      radar: ["radar", "select", radarOn ? "on" : "off", ["on", "off"]],
      quality: ["camera quality", "select", rig.quality || "default", ["default", ...this.state.choices.camera_quality], "not a camera quality"],
    };
    const users = (this.state.doc.vessels || []).filter((v) => v.rig === name).map((v) => v.id);
    const n = Array.isArray(rig.cameras) ? rig.cameras.length : null;
    const cams = n !== null ? `${n} camera${n === 1 ? "" : "s"}` : (rig.preset || "full") === "full" ? "4 surround cameras" : "no cameras";
    // a camera or the top view that sets a quality of its own renders at it, whatever the rig's select says
    const own = [...(Array.isArray(rig.cameras) ? rig.cameras : []).map((c) => [c?.name, c?.quality]), ["top view", rig.top_view?.quality]]
      .filter(([, q]) => typeof q === "string" && q !== (rig.quality || "standard"))
      .map(([cam, q]) => `${cam} ${q}`);
    const quality = own.length ? ` (own quality: ${own.join(", ")})` : "";
    const summary = `${cams}${quality}; carried by ${users.length ? users.join(", ") : "no vessel"}. Other sensor settings: edit the YAML.`;
    return { fields, summary };
  }

  renderRigs() {
    const box = $("rigs");
    const rigs = this.state.doc.rigs || {};
    const names = Object.keys(rigs);
    const shown = [...box.children].map((div) => div.dataset.rig);
    const focused = box.contains(document.activeElement) ? document.activeElement : null;
    if (focused && names.length === shown.length && names.every((name, i) => name === shown[i])) {
      // The person is in one of the rigs' fields, which is left as it is; the others and the summaries follow the
      // scenario (a preset picked here kept saying "radar: on" and "4 surround cameras" of a LiDAR-only rig, and a
      // quality picked kept the summary of the one before, until another edit after the focus had left).
      for (const div of box.children) {
        const { fields, summary } = this.rigView(div.dataset.rig, rigs[div.dataset.rig]);
        for (const input of div.querySelectorAll("[data-key]")) {
          // a select's pick is in the scenario once made (an undo from it shows the value undone); a box being typed
          // into is not touched
          const [, , shownValue, , why] = fields[input.dataset.key];
          if (input.tagName === "SELECT") selectValue(input, String(shownValue), why);
          else setValue(input, String(shownValue));
        }
        div.querySelector(".summary").textContent = summary;
      }
      return;
    }
    // Another set of rigs (one removed with its button, which held the focus: it stayed on the page): built again,
    // the focus given back to the same control where it is still there.
    const again = focused && focused.closest("[data-rig]")
      ? `[data-rig="${CSS.escape(focused.closest("[data-rig]").dataset.rig)}"] ${focused.dataset.key ? `[data-key="${CSS.escape(focused.dataset.key)}"]` : "button[data-action=remove]"}`
      : null;
    box.replaceChildren();
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
      del.setAttribute("aria-label", `Remove rig ${name}`); // which of the rigs, to a screen reader too
      head.appendChild(del);
      const grid = document.createElement("div");
      grid.className = "grid";
      const { fields, summary: text } = this.rigView(name, rig);
      for (const [key, [label, kind, value, options, placeholder]] of Object.entries(fields)) {
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
        if (kind === "select") selectValue(input, String(value), placeholder);
        else input.value = String(value);
        input.dataset.key = key;
        input.dataset.field = `rigs.${name}.${key}`;
        if (kind !== "select" && this.refused.has(input.dataset.field)) input.dataset.refused = "1";
        l.appendChild(input);
        grid.appendChild(l);
      }
      const summary = document.createElement("div");
      summary.className = "summary";
      summary.textContent = text;
      div.append(head, grid, summary);
      box.appendChild(div);
    }
    if (again) box.querySelector(again)?.focus();
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
        const n = input.dataset.number === "" ? null : Number(input.dataset.number);
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
    const WHOLE = "a whole number, 0 or more (empty: 0)";
    $("s-name").addEventListener("change", (ev) => edit((d) => {
      d.name = ev.target.value.trim();
    }));
    $("s-seed").addEventListener("change", (ev) => {
      const n = this.readNumber(ev.target, "seed", WHOLE);
      if (n !== undefined) edit((d) => {
        d.seed = n ?? 0;
      });
    });
    $("s-comment").addEventListener("change", (ev) => {
      // an edit as any other: undone by Undo, and the unsaved mark follows it (state.dirty compares the scenario)
      this.state.edit(() => {
        this.state.comment = ev.target.value;
      });
    });
    $("m-type").addEventListener("change", (ev) => edit((d) => {
      d.map = { ...d.map, type: ev.target.value };
      delete d.map.params; // parameters belong to one map type
    }));
    $("m-seed").addEventListener("change", (ev) => {
      const n = this.readNumber(ev.target, "map seed", WHOLE);
      if (n !== undefined) edit((d) => {
        d.map = { ...d.map, seed: n ?? 0 };
      });
    });
    $("m-params").addEventListener("change", (ev) => {
      const text = ev.target.value.trim();
      let params;
      try {
        params = text ? JSON.parse(text) : null;
      } catch (err) {
        this.refuse(ev.target, `map parameters: not JSON (${err.message}); type a JSON object such as {"name": value}, or leave it empty for the map's defaults. The map keeps its parameters.`);
        return;
      }
      if (params !== null && (typeof params !== "object" || Array.isArray(params))) {
        this.refuse(ev.target, `map parameters: ${text} is not a JSON object; type one such as {"name": value}, or leave it empty for the map's defaults. The map keeps its parameters.`);
        return;
      }
      const huge = nonFinite(params);
      if (huge !== null) {
        this.refuse(ev.target, `map parameters: ${huge} is too large to be a number (beyond ±1.8e308); type a finite number. The map keeps its parameters.`);
        return;
      }
      this.accept(ev.target);
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
    $("e-time").addEventListener("change", (ev) => {
      // A box cleared, or one part of it (Backspace on the hours), reads as "": that was the time deleted, the
      // schema's noon put in its place while the box showed --:-- (a night scenario saved as a midday one).
      const box = ev.target;
      if (box.value === "") {
        const what = box.validity?.badInput ? "incomplete" : "empty";
        const now = this.state.doc.environment?.time_of_day ?? "12:00";
        this.refuse(box, `time of day: ${what}; type a 24-hour time, 00:00 to 23:59. The scenario keeps its time (${now}).`);
        return;
      }
      this.accept(box);
      env("time_of_day", box.value);
    });
    $("e-weather").addEventListener("change", (ev) => env("weather", ev.target.value));
    const waveAllowed = () => {
      const [lo, hi] = this.waveRange();
      return `a wave height in metres, ${lo} to ${hi}, or pick a preset`;
    };
    const inRange = (n) => n >= this.waveRange()[0] && n <= this.waveRange()[1];
    // a wave picked replaces a `sea` (a scenario gives one or the other)
    const setWave = (value) => {
      this.forgetRefused("environment.sea");
      this.waveBeforeSea = undefined;
      edit((d) => {
        d.environment ||= {};
        d.environment.wave = value;
        delete d.environment.sea;
      });
    };
    $("e-wave").addEventListener("change", (ev) => {
      const select = ev.target;
      if (select.value === "sea") return; // shown only while the sea sets the waves
      if (select.value !== "custom") {
        this.forgetRefused("environment.wave");
        return setWave(select.value);
      }
      // from a preset to a custom wave: its height is asked for here, then changed in the box beside the select
      const now = this.state.doc.environment?.wave ?? "W0";
      const preset = this.state.choices.wave.find((w) => w.name === now);
      const [lo, hi] = this.waveRange();
      const h = window.prompt(`Wave height in metres (${lo} to ${hi})`, String(preset ? preset.height_m : typeof now === "number" ? now : 1));
      const n = h === null || h.trim() === "" ? NaN : Number(h.trim());
      if (Number.isFinite(n) && inRange(n)) {
        this.forgetRefused("environment.wave");
        setWave(n);
      } else {
        if (h !== null && h.trim() !== "") {
          const what = Number.isFinite(n) ? `${n} m is out of range` : `${JSON.stringify(h.trim())} is not a number`;
          this.refused.set("environment.wave", `wave: ${what}; type ${waveAllowed()}. The wave stays as it was.`);
        }
        select.value = this.waveChoice(); // back to the wave the scenario has (the select keeps the focus)
        this.renderNotes();
      }
    });
    $("e-wave-height").addEventListener("change", (ev) => {
      const n = this.readNumber(ev.target, "wave height", waveAllowed(), { required: true });
      if (n === undefined) return;
      if (!inRange(n)) {
        this.refuse(ev.target, `wave height: ${n} m is out of range; type ${waveAllowed()}. The wave stays as it was.`);
        return;
      }
      env("wave", n);
    });
    $("e-motion").addEventListener("change", (ev) => env("motion", ev.target.value === "physical" ? null : ev.target.value));
    $("e-sea").addEventListener("change", (ev) => {
      const text = ev.target.value.trim();
      const allowed = 'type a JSON object such as {"state": 5} (a WMO sea state, 0 to 9) or {"hs_m": 2, "tp_s": 7.5}, or leave it empty for the wave\'s sea. The sea stays as it was.';
      let sea;
      try {
        sea = text ? JSON.parse(text) : null;
      } catch (err) {
        this.refuse(ev.target, `sea: not JSON (${err.message}); ${allowed}`);
        return;
      }
      if (sea !== null && !isMapping(sea)) {
        this.refuse(ev.target, `sea: ${text} is not a JSON object; ${allowed}`);
        return;
      }
      const huge = nonFinite(sea);
      if (huge !== null) {
        this.refuse(ev.target, `sea: ${huge} is too large to be a number (beyond ±1.8e308); ${allowed}`);
        return;
      }
      this.accept(ev.target);
      edit((d) => {
        d.environment ||= {};
        if (sea === null) {
          delete d.environment.sea;
          // the wave the scenario had before a sea was typed comes back (clearing the sea left W0, a review's)
          if (this.waveBeforeSea !== undefined) d.environment.wave = this.waveBeforeSea;
          this.waveBeforeSea = undefined;
        } else {
          if (!isMapping(d.environment.sea) && d.environment.wave !== undefined) this.waveBeforeSea = d.environment.wave;
          d.environment.sea = sea;
          delete d.environment.wave; // the sea replaces the wave: the default, W0, is the one that goes with a sea
        }
      });
    });
    const envNumber = (key, label, allowed) => (ev) => {
      const n = this.readNumber(ev.target, label, allowed);
      if (n !== undefined) env(key, n);
    };
    $("e-visibility").addEventListener("change", envNumber("visibility_m", "visibility", "metres, 1 or more (empty: the weather's own)"));
    $("e-rain").addEventListener("change", envNumber("rain_mm_per_h", "rain", "mm/h, 0 to 500 (empty: the weather's own)"));
    $("e-latitude").addEventListener("change", envNumber("latitude_deg", "latitude", "degrees north, -90 to 90 (empty: 45)"));
    $("e-day").addEventListener("change", envNumber("day_of_year", "day of year", "a whole number, 1 to 366 (empty: 172, 21 June)"));
    const acq = (key, label, allowed) => (ev) => {
      const n = this.readNumber(ev.target, label, allowed);
      if (n !== undefined) edit((d) => {
        d.acquisition ||= {};
        if (n === null) delete d.acquisition[key];
        else d.acquisition[key] = n;
      });
    };
    $("a-frequency").addEventListener("change", acq("frequency_hz", "frequency", "Hz, 0.01 to 1000 (empty: 5)"));
    $("a-frames").addEventListener("change", acq("frames", "frames", "a whole number of frames, 1 or more (empty: 100)"));
    $("rigs").addEventListener("change", (ev) => {
      const input = ev.target;
      const key = input.dataset.key;
      const rig = input.closest("[data-rig]")?.dataset.rig;
      if (!key || !rig) return;
      if (input.tagName === "INPUT") {
        const [label, allowed] = key === "lidar.channels"
          ? ["LiDAR channels", "a whole number of channels, 1 or more (empty: the preset's)"]
          : ["LiDAR range", "metres, more than 0 (empty: the preset's)"];
        const n = this.readNumber(input, `${rig} ${label}`, allowed);
        if (n === undefined) return;
        input.dataset.number = n === null ? "" : String(n);
      }
      this.editRig(rig, key, input);
    });
    $("rigs").addEventListener("click", (ev) => {
      const b = ev.target.closest("button[data-action=remove]");
      if (!b) return;
      const name = b.closest("[data-rig]").dataset.rig;
      const users = (this.state.doc.vessels || []).filter((v) => v.rig === name).map((v) => v.id);
      if (users.length) {
        // removed, its vessels were left without a rig, which is the paper's full suite: a LiDAR-only USV became a
        // fully instrumented one without a word (a review's)
        this.state.emit("status", {
          text: `rig ${name} is carried by ${users.join(", ")}: give ${users.length === 1 ? "that vessel" : "those vessels"} another rig first (a USV without one carries the paper's full suite); not removed`,
          error: true,
        });
        return;
      }
      this.forgetRefused(`rigs.${name}.`);
      edit((d) => {
        delete d.rigs[name];
      });
    });
    $("rig-add").addEventListener("click", () => {
      const box = $("rig-new-name");
      const rigs = Object.keys(this.state.doc.rigs || {});
      let name = box.value.trim();
      if (!name) for (let k = rigs.length + 1; !name || rigs.includes(name); k++) name = `rig_${k}`;
      if (!RIG_NAME.test(name)) {
        this.refuse(box, `rig name ${JSON.stringify(name)}: letters, digits, _ and - only (1 to 64 characters); no rig added.`);
        return;
      }
      if (rigs.includes(name)) {
        this.refuse(box, `rig name ${JSON.stringify(name)}: this scenario has a rig of that name; give the new rig another. No rig added.`);
        return;
      }
      this.accept(box);
      edit((d) => {
        d.rigs ||= {};
        d.rigs[name] = {};
      });
      box.value = "";
      this.renderNotes();
    });
  }
}
