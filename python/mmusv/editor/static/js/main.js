// Boots the editor: loads the choices, the vessel library and the first scenario, then wires the toolbar (open,
// save, undo, preview, run), the timeline and the keyboard. window.mmusvEditor exposes the state and the view for
// people poking at the page from the browser console (and for the browser tests).

import { api } from "./api.js";
import { MapView } from "./mapview.js";
import { Panels } from "./panels.js";
import { EditorState } from "./state.js";

const $ = (id) => document.getElementById(id);
const state = new EditorState();
const map = new MapView(state, $("map"));
const panels = new Panels(state, map);
let bundled = [];
let runTimer = null;
let currentRun = null;
let runAfterSave = null; // {frames}: the run to start once the file is saved over (Run, then Overwrite)

/** Shows `text` in the status (role=status: a screen reader reads it out); `detail`, read out after it, is not
 * shown (the page shows it elsewhere, and a longer status would wrap and move the map under the pointer). */
function status(text, error = false, detail = "") {
  const s = $("status");
  s.textContent = text;
  if (detail) {
    const more = document.createElement("span");
    more.className = "sr-only";
    more.textContent = ` ${detail}`;
    s.appendChild(more);
  }
  s.classList.toggle("error", error);
}
state.on("status", ({ text, error }) => status(text, error));

/** Marks the toolbar box `id` (the file name, the run's frames) as the one the status's error is about: invalid,
 * described by the status, and focused so that the person can fix it there; `false` takes the mark away. */
function markField(id, bad) {
  const box = $(id);
  if (!bad) {
    box.removeAttribute("aria-invalid");
    if (box.getAttribute("aria-describedby") === "status") box.removeAttribute("aria-describedby");
    return;
  }
  box.setAttribute("aria-invalid", "true");
  box.setAttribute("aria-describedby", "status");
  box.focus();
}

/** Hides the box that asks whether to overwrite a file; the keyboard, when it was on one of its buttons, goes on at
 * `then` (not at the top of the page, where a hidden button leaves it). */
function hideConfirm(then) {
  const box = $("save-confirm");
  const had = box.contains(document.activeElement);
  box.hidden = true;
  $("save-overwrite").textContent = "Overwrite";
  if (had && then) then.focus();
}

// ------------------------------------------------------------------------------------- map layers

// A scenario opened: the map shows it whole once its map is there (the view of the scenario shown before may miss
// it, on another part of the map or on another map).
let fitOnMap = false;

async function ensureMap() {
  const m = state.doc?.map;
  if (!m) return;
  const key = JSON.stringify([m.type, m.seed, m.params || {}]);
  if (key === state.mapKey) {
    if (fitOnMap && state.mapLayers) {
      fitOnMap = false;
      map.fitScenario();
    }
    return; // the same map (a request for it in flight fits the scenario when it is there)
  }
  state.mapKey = key;
  status("generating the map…");
  try {
    const layers = await api.map({ type: m.type, seed: m.seed, ...(m.params ? { params: m.params } : {}) });
    if (state.mapKey !== key) return;
    const first = !state.mapLayers;
    state.mapLayers = layers;
    map.renderMap();
    if (first || fitOnMap) map.fitScenario();
    fitOnMap = false;
    map.renderScreen();
    const shown = `${layers.kind.replace("_", " ")} map, seed ${layers.seed}, ${layers.extent} m square`;
    // a map slower than the check must not hide the check's verdict: both are said
    if (!state.pending() && (state.evaluation || state.evalError)) showCheck(`${shown} · `);
    else status(shown);
  } catch (err) {
    if (state.mapKey === key && fitOnMap) {
      fitOnMap = false;
      map.fitScenario(); // the routes, without their map
    }
    status(`map: ${err.message}`, true);
  }
}

// ------------------------------------------------------------------------------------- timeline

function renderTimeline() {
  const ev = state.evaluation?.valid ? state.evaluation : state.lastGood;
  const frames = ev?.frames || state.doc?.acquisition?.frames || 1;
  const f = ev?.frequency_hz || state.doc?.acquisition?.frequency_hz || 5;
  const slider = $("frame");
  slider.max = String(Math.max(0, frames - 1));
  if (document.activeElement !== slider) slider.value = String(state.frame);
  $("frame-text").textContent = `frame ${state.frame} / ${frames - 1} · t = ${(state.frame / f).toFixed(2)} s`;
}

let playing = null;
function togglePlay() {
  if (playing) {
    cancelAnimationFrame(playing.raf);
    playing = null;
    $("play").textContent = "Play";
    return;
  }
  const ev = state.evaluation?.valid ? state.evaluation : null;
  if (!ev) {
    // nothing to play yet: say why, rather than a button that does nothing
    if (state.pending()) status("play: the scenario is being checked; press Play again when the check has ended", true);
    else status("play: the scenario does not validate, so it has no motion to play; fix the errors listed under Checks", true);
    return;
  }
  $("play").textContent = "Pause";
  const t0 = performance.now(), k0 = state.frame >= ev.frames - 1 ? 0 : state.frame;
  const step = () => {
    // an edit of the acquisition (frames, frequency) while playing: stop at a frame the scenario has
    const now = state.evaluation;
    if (now && (!now.valid || now.frames !== ev.frames || now.frequency_hz !== ev.frequency_hz)) {
      if (now.valid && state.frame > now.frames - 1) state.setFrame(now.frames - 1);
      return togglePlay();
    }
    const k = Math.min(ev.frames - 1, k0 + Math.floor(((performance.now() - t0) / 1000) * ev.frequency_hz));
    if (k !== state.frame) state.setFrame(k);
    if (k >= ev.frames - 1) return togglePlay();
    playing.raf = requestAnimationFrame(step);
  };
  playing = { raf: requestAnimationFrame(step) };
}

// ------------------------------------------------------------------------------------- open and save

let listsReading = 0; // folder listings asked for and not yet shown (#open's data-listing says "reading" meanwhile)

/** Lists the folder's files and the bundled scenarios in the Open box, the value picked kept where still listed. */
async function refreshOpen() {
  const sel = $("open");
  listsReading += 1;
  sel.dataset.listing = "reading";
  try {
    listOpen(sel, await api.files());
  } finally {
    listsReading -= 1;
    sel.dataset.listing = listsReading ? "reading" : "done";
  }
}

function listOpen(sel, files) {
  const keep = sel.value;
  sel.replaceChildren();
  const head = document.createElement("option");
  head.value = "";
  head.textContent = "open…";
  sel.appendChild(head);
  const group = (label, items) => {
    const g = document.createElement("optgroup");
    g.label = label;
    for (const [value, text] of items) {
      const o = document.createElement("option");
      o.value = value;
      o.textContent = text;
      g.appendChild(o);
    }
    sel.appendChild(g);
  };
  group("this folder", files.map((f) => [`file:${f.name}`, f.name]));
  group("bundled scenarios", bundled.map((b) => [`bundled:${b.name}`, `${b.name} (${b.map}, ${b.usvs} USVs, ${b.targets} targets)`]));
  sel.value = keep && [...sel.options].some((o) => o.value === keep) ? keep : "";
}

/** The entries of `doc`'s `assets:` (its own asset files), as the library is asked for them, and their key. */
function assetEntries(doc) {
  const entries = Array.isArray(doc?.assets) ? doc.assets.filter((e) => typeof e === "string") : [];
  return { entries, key: JSON.stringify(entries) };
}

// Each scenario asked to be shown takes a number, and is shown only while its number is the last one asked: the Open
// box's arrow keys open each file they pass, and a file's reply coming in after a later one's showed that file, not
// the one picked last.
let showAsked = 0;

/** Shows the scenario `opened` (state.load's argument) with its own library: the built-in assets and its asset
 * files' (the library loaded once at the start listed the assets the server held then, so a scenario opened later
 * lacked its own and listed another's, refused as "unknown asset" once placed). Both are shown at once, never the
 * new scenario with the library of the one before. Rejects, showing nothing new, when the library cannot be had;
 * resolves false, showing nothing, where another scenario was asked for since `asked` (`showAsked`). */
async function show(opened, asked = ++showAsked) {
  const { entries, key } = assetEntries(opened.document);
  const assets = await api.assets(entries);
  if (asked !== showAsked) return false; // another scenario was asked for meanwhile
  panels.setAssets(assets, key);
  state.load(opened);
  return true;
}

// A change of the scenario's `assets:` (none of the page's forms makes one; an undo could): its library again
let libraryAsked = null;
async function refreshLibrary() {
  const { entries, key } = assetEntries(state.doc);
  if (key === panels.assetsKey || key === libraryAsked) return;
  libraryAsked = key;
  try {
    const assets = await api.assets(entries);
    if (assetEntries(state.doc).key === key) {
      panels.setAssets(assets, key);
      panels.renderVessel(); // the selected vessel's asset in the new menu, or said to be missing from it
    }
  } catch (err) {
    status(`vessel library: ${err.message}`, true);
  } finally {
    if (libraryAsked === key) libraryAsked = null;
  }
}

/** Loads `value` (`file:NAME` or `bundled:NAME`, as the Open box names them); rejects when it cannot. Resolves
 * false, showing nothing, where another scenario was asked for before it came (`showAsked`). */
async function load(value) {
  const asked = ++showAsked;
  const [kind, name] = [value.slice(0, value.indexOf(":")), value.slice(value.indexOf(":") + 1)];
  let res;
  try {
    res = kind === "file" ? await api.readFile(name) : await api.bundledOne(name);
  } catch (err) {
    if (asked !== showAsked) return false; // not the scenario asked for last: nothing to say of it
    throw err;
  }
  if (asked !== showAsked) return false;
  const shown = await show(
    {
      document: res.document,
      comment: res.comment,
      comments: res.comments,
      name: res.name,
      savedName: kind === "file" ? res.name : null,
    },
    asked,
  );
  if (!shown) return false;
  savedEtag = kind === "file" ? res.etag : null;
  openedBundled = kind === "bundled" ? name : null;
  bootNote = "";
  newNote = "";
  remember();
  status(`opened ${kind === "file" ? name : `bundled ${name}`}${res.valid ? "" : " (it does not validate: see Checks)"}`);
  return true;
}

/** Names the scenario open in the page's address (#file:NAME or #bundled:NAME), so a reload opens it again. */
function remember() {
  const [kind, name] = state.savedName ? ["file", state.savedName] : ["bundled", openedBundled];
  const hash = name ? `#${kind}:${encodeURIComponent(name)}` : "";
  history.replaceState(null, "", `${location.pathname}${location.search}${hash}`);
}
let openedBundled = null; // the bundled scenario last opened, while no folder file holds the scenario
let bootNote = ""; // why the scenario the address named (a reload) did not open: said with the checks (showCheck)
// the command line named a file that does not exist yet: the page shows a new scenario, and says so with the checks
// (whose verdict, "does not validate" as it has no vessel yet, said nothing of it) until it is edited or saved
let newNote = "";

async function open(value) {
  if (!value) return;
  if (state.dirty && !window.confirm("Discard the unsaved changes?")) {
    $("open").value = ""; // the scenario shown is still the one edited, not the one picked
    return;
  }
  try {
    if ((await load(value)) && state.savedName && currentRun?.status !== "running") await showLastRun();
  } catch (err) {
    status(err.message, true);
  }
  $("open").value = "";
}

/** The address edited by hand (#file:NAME or #bundled:NAME, Enter in the address bar, or Back to such an address)
 * opens what it names, asking first when there are unsaved changes, as the Open box does; it changed the address
 * only, and the page went on showing (and saving) the scenario it had. The address goes back to the scenario shown
 * when it names none, or the person keeps the changes, or it cannot be opened. */
async function openAddress() {
  let asked = "";
  try {
    asked = decodeURIComponent(location.hash.slice(1));
  } catch {
    // not percent-encoded text: said below
  }
  if (!/^(file|bundled):./.test(asked)) {
    if (location.hash.length > 1) {
      status(`the address ${location.hash} names no scenario: use #file:NAME.yaml (a file of the folder) or #bundled:NAME`, true);
    }
    remember();
    return;
  }
  await open(asked);
  remember();
}

/** Shows the latest run of the file open (one that ended too, as a run that just ended shows); else a run going
 * on, of any file (started before the page was loaded again, or from another tab). */
async function showLastRun() {
  const runs = await api.runs(); // newest first
  const run = (state.savedName && runs.find((j) => j.scenario === state.savedName)) || runs.find((j) => j.status === "running");
  if (run) follow(run);
}

// The ETag of the folder file this page last read or saved (state.savedName): a save of that file sends it, so a
// version saved meanwhile by another tab or program is never overwritten without asking (412 from the server).
let savedEtag = null;

async function save(overwrite = false) {
  const name = $("file-name").value.trim();
  hideConfirm($("save"));
  if (!name) {
    status("give the file a name ending in .yaml (letters, digits, _ - and .) in the File box: it is empty; not saved", true);
    markField("file-name", true);
    return false;
  }
  try {
    const same = name === state.savedName;
    const key = state.key(); // what is sent: edits made while it is on its way are not saved
    const sent = state.comments;
    const body = { document: state.doc, comment: state.comment, comments: sent, overwrite: overwrite || same };
    const res = await api.writeFile(name, body, same && !overwrite ? savedEtag : null);
    savedEtag = res.etag;
    markField("file-name", false);
    // as the file now holds them (a removed vessel's at its end); but not over anchors changed while the save was on
    // its way (a vessel renamed then: the answer's are at its old id, and the next save would move them to the end)
    if (state.comments === sent) state.comments = res.comments || [];
    state.savedName = name;
    state.fileName = name;
    state.markSaved(key);
    bootNote = "";
    newNote = "";
    remember();
    renderAll(); // the title's unsaved mark and file name
    status(`saved ${res.name} (${res.bytes} bytes)${res.note ? `; ${res.note}` : ""}`);
    document.body.dataset.saved = name;
    await refreshOpen();
    return true;
  } catch (err) {
    if (err.status === 409) {
      // (and the status no longer shows what an earlier attempt said)
      status(`not saved: ${name} exists; Overwrite replaces it, Cancel keeps it (then give another file name)`, true);
      $("save-confirm-text").textContent = `${name} exists.`;
      $("save-confirm").hidden = false;
    } else if (err.status === 412) {
      status(`not saved: ${err.message}`, true);
      // (a file deleted or renamed since is no file "changed": Overwrite creates it again)
      const gone = (await api.files().catch(() => null))?.every((f) => f.name !== name);
      $("save-confirm-text").textContent = gone
        ? `${name} is no longer in the folder (deleted or renamed since you opened it); Overwrite saves it again.`
        : `${name} was changed by another tab or program since you opened it.`;
      $("save-confirm").hidden = false;
    } else {
      // (the server's "NAME: not saved, the scenario does not validate: ..." read "not saved: NAME: not saved, ...")
      status(`not saved: ${err.message.replace(/^([^:\s]+): not saved, /, "$1: ")}`, true);
      if (err.status === 400 && err.message.startsWith("file name")) markField("file-name", true);
    }
    return false;
  }
}

// ------------------------------------------------------------------------------------- preview and run

// The element that had the focus when the preview opened (the Preview button): it gets it back when it closes.
let previewOpener = null;

/** The controls of the preview window a Tab reaches, in order. */
function previewStops() {
  const sel = 'button, [href], input, select, textarea, [tabindex]:not([tabindex="-1"])';
  return [...$("preview-modal").querySelectorAll(sel)].filter((el) => !el.disabled && !el.closest("[hidden]"));
}

function closePreview() {
  if ($("preview-modal").hidden) return;
  $("preview-modal").hidden = true;
  const back = previewOpener?.isConnected ? previewOpener : $("preview");
  previewOpener = null;
  back.focus();
}

// Each preview asked for takes a number; a reply is shown only while its number is the last one asked (a preview
// renders for seconds: closed and asked again for another frame, the first reply came in after the second and took
// its place under the second's title).
let previewAsked = 0;

async function preview() {
  const asked = ++previewAsked;
  const usvs = (state.doc?.vessels || []).filter((v) => v.role === "usv").map((v) => v.id);
  const agent = usvs.includes(state.selected) ? state.selected : usvs[0];
  if ($("preview-modal").hidden) previewOpener = document.activeElement;
  $("preview-modal").hidden = false;
  $("preview-close").focus(); // the keyboard is in the window (Escape or Close leaves it)
  $("preview-img").hidden = true;
  $("preview-wait").hidden = false;
  $("preview-wait").textContent = "Rendering with the real sensors…";
  $("preview-title").textContent = `Preview · ${agent || "no USV"} · frame ${state.frame}`;
  try {
    const blob = await api.preview(state.doc, state.frame, agent || null);
    if (asked !== previewAsked) return;
    const img = $("preview-img");
    if (img.src) URL.revokeObjectURL(img.src);
    img.src = URL.createObjectURL(blob);
    img.onload = () => {
      if (asked !== previewAsked) return; // loaded as another preview was asked for: that one's wait stays
      $("preview-wait").hidden = true;
      img.hidden = false;
    };
  } catch (err) {
    if (asked !== previewAsked) return;
    $("preview-wait").textContent = `No preview: ${err.message}`;
  }
}

/** Whether `job` is an older word on the run shown than the one shown: replies come back out of order (the stop's
 * reply is the run as it was when the stop came, still running; a slow poll's reply is older than the next one's).
 * One coming after the poll that saw the run end put it back to running, and nothing polled it again. */
function stale(job) {
  if (!currentRun || currentRun.id !== job.id || job.status !== "running") return false;
  return currentRun.status !== "running" || job.done < currentRun.done;
}

function showRun(job) {
  if (stale(job)) return;
  currentRun = job;
  const box = $("run-status");
  box.hidden = false;
  box.className = `run-status ${job.status}`;
  box.dataset.status = job.status;
  const p = $("run-progress");
  p.max = job.total || 1;
  p.value = job.done;
  $("run-stop").hidden = job.status !== "running";
  let text = `${job.status} · frame ${job.done}${job.total ? ` / ${job.total}` : ""}`;
  const frames = `${job.done} frame${job.done === 1 ? "" : "s"}`;
  if (job.status === "complete") {
    text = job.earlier
      ? `done: ${frames} → ${job.output}/ (recorded before this editor started)`
      : `done: ${frames} in ${job.seconds} s → ${job.output}/`;
  }
  if (job.status === "failed" || job.status === "interrupted") text = `${job.status}: ${job.error}`;
  $("run-text").textContent = text;
  $("run-text").title = `${job.command}${job.warnings.length ? "\n" + job.warnings.join("\n") : ""}`;
}

async function run() {
  // A number box the browser cannot read (e.g. "1e") reports "" — which would mean every frame: say so instead.
  const box = $("run-frames");
  const framesText = box.value.trim();
  const frames = framesText ? Number(framesText) : null;
  if (box.validity.badInput || (frames !== null && !(Number.isInteger(frames) && frames >= 1))) {
    status("not run: Frames must be a whole number of frames (1 or more); leave it empty to run every frame", true);
    markField("run-frames", true);
    return;
  }
  markField("run-frames", false);
  runAfterSave = null;
  if (!(await save(false))) {
    // the file exists or changed: the Overwrite button saves it and then starts the run asked for
    if (!$("save-confirm").hidden) {
      runAfterSave = { frames };
      $("save-overwrite").textContent = "Overwrite and run";
    }
    return;
  }
  await startRun(frames);
}

async function startRun(frames) {
  try {
    follow(await api.startRun(state.savedName, frames));
  } catch (err) {
    status(`run: ${err.message}`, true);
  }
}

/** Shows the run `job` and its progress until it ends. */
function follow(job) {
  showRun(job);
  clearInterval(runTimer);
  if (job.status !== "running") return;
  runTimer = setInterval(async () => {
    try {
      const j = await api.run(job.id);
      showRun(j);
      if (j.status !== "running") {
        clearInterval(runTimer);
        // the run's end replaces what the status said meanwhile (a refused second Run: "… wait for it to end")
        status(`run of ${j.scenario}: ${$("run-text").textContent}`, j.status === "failed" || j.status === "interrupted");
      }
    } catch (err) {
      clearInterval(runTimer);
      status(err.message, true);
    }
  }, 400);
}

// ------------------------------------------------------------------------------------- wiring

function renderAll() {
  panels.renderFleet();
  panels.renderVessel();
  panels.renderProblems();
  panels.renderScenario();
  panels.renderNotes();
  map.renderScenario();
  renderTimeline();
  $("undo").disabled = !state.undoStack.length;
  $("redo").disabled = !state.redoStack.length;
  if (document.activeElement !== $("file-name")) $("file-name").value = state.fileName;
  document.title = `${state.dirty ? "● " : ""}${state.fileName || "scenario"} · mmusv editor`;
}

/** Ends drawing a route when its vessel is gone (deleted, its placing undone, another scenario opened): the hint
 * "Click to add waypoints to usv_1" stayed, and the next click on the map only ended the drawing. While it is being
 * drawn the route is the selected vessel's: the hint follows a rename (or another vessel picked from the list, which
 * the clicks then add to). Run after the edit's own handlers (a rename selects the new id after the edit). */
function followDrawing() {
  queueMicrotask(() => {
    if (map.mode !== "draw") return;
    if (!state.vessel(state.selected)) map.setMode("select");
    else if (map.drawing !== state.selected) map.setMode("draw", { vessel: state.selected });
  });
}

state.on("loaded", () => {
  fitOnMap = true;
  ensureMap();
  followDrawing();
});
state.on("doc", () => {
  followDrawing();
  refreshLibrary();
  if (state.undoStack.length) bootNote = newNote = ""; // an edit of the scenario shown instead, or of the new one
  ensureMap();
  renderAll();
});
state.on("evaluated", () => {
  renderAll();
  showCheck();
});
/** Says the last check's verdict in the status line, after `prefix` (the map just shown, say), and after why the
 * scenario the page's address names did not open, until the scenario shown instead is edited or another is opened
 * (the check's verdict replaced it at once: the person saw another scenario, without a word why). */
function showCheck(prefix = "") {
  const ev = state.evaluation;
  const note = bootNote ? `${bootNote}; showing ${state.fileName || "another scenario"} instead · ` : "";
  prefix = `${note}${newNote ? `${newNote} · ` : ""}${prefix}`;
  if (!ev) status(`${prefix}cannot check: ${state.evalError}`, true);
  else if (!ev.valid) {
    // read out with the first error, its field and what it allows (seen next to the field and under Checks)
    const first = ev.errors[0] ? `First: ${ev.errors[0].message}.` : "";
    const more = ev.errors.length > 1 ? ` ${ev.errors.length - 1} more under Checks.` : "";
    status(`${prefix}${ev.errors.length} error(s): the scenario does not validate`, true, `${first}${more}`);
  }
  else {
    const errors = ev.problems.filter((p) => p.severity === "error").length;
    status(`${prefix}${ev.vessels.length} vessels · ${ev.frames} frames · ${errors} error(s), ${ev.problems.length - errors} warning(s)`, errors > 0 || !!note);
  }
}
/** Scrolls the left panel so that the Selected vessel panel is seen (a vessel picked on the map or in a list may
 * have it below the panel's fold). Scrolling moves no focus: a selection from the map keeps the keyboard there. The
 * panel is left where it is when it is seen whole already or the keyboard is in it (its id renamed, say). */
function revealVesselPanel() {
  const panel = $("vessel-panel");
  if (panel.hidden || panel.contains(document.activeElement)) return;
  const scroller = panel.closest(".panel");
  if (!scroller) return;
  const r = panel.getBoundingClientRect();
  const s = scroller.getBoundingClientRect();
  if (r.top >= s.top && r.bottom <= s.bottom) return;
  panel.scrollIntoView({ block: r.height <= s.height ? "nearest" : "start" });
}
let revealedSelection = null; // the vessel whose selection last brought the panel into view
state.on("selection", () => {
  followDrawing();
  panels.renderFleet();
  panels.renderVessel();
  panels.renderNotes();
  map.renderScenario();
  if (state.selected !== revealedSelection) {
    revealedSelection = state.selected;
    if (state.selected) revealVesselPanel();
  }
});
state.on("frame", () => {
  map.renderFrame();
  renderTimeline();
});
state.on("mode", ({ mode, asset, vessel }) => {
  const box = $("drawing");
  box.hidden = mode === "select";
  $("drawing-text").textContent = mode === "place"
    ? `Click the map to place ${asset.name} (${asset.length} × ${asset.beam} m), or Enter on the map: at the cross in its middle`
    : mode === "draw" ? `Click to add waypoints to ${vessel} (Space on the map: at the cross); double-click or Enter to finish` : "";
  $("mode-hint").textContent = mode === "select"
    ? "Pick a vessel, then click the map to place it and click again to add waypoints."
    : $("drawing-text").textContent;
  panels.renderLibrary();
});

$("open").addEventListener("change", (ev) => open(ev.target.value));
window.addEventListener("hashchange", () => {
  if (document.body.dataset.ready === "1") openAddress(); // (while booting, boot reads the address itself)
});
// the folder's files as they are when the list is reached (one another tab or program saved since was missing)
$("open").addEventListener("focus", () => refreshOpen().catch((err) => status(`open: ${err.message}`, true)));
$("file-name").addEventListener("change", (ev) => {
  state.fileName = ev.target.value.trim();
});
$("file-name").addEventListener("input", () => markField("file-name", false));
$("run-frames").addEventListener("input", () => markField("run-frames", false));
$("save").addEventListener("click", () => {
  runAfterSave = null;
  save(false);
});
$("save-overwrite").addEventListener("click", async () => {
  const then = runAfterSave;
  runAfterSave = null;
  if ((await save(true)) && then) await startRun(then.frames);
});
// Cancel (or Escape) keeps the file: the keyboard goes to the file name, to give another
function cancelConfirm() {
  runAfterSave = null;
  hideConfirm($("file-name"));
  status("not saved: the file was kept as it is; give another file name to save under it");
}
$("save-cancel").addEventListener("click", cancelConfirm);
/** Whether Escape is the overwrite question's: the keyboard is on the question, on the toolbar box or button that
 * asked it (file name, Save, Frames, Run) or on nothing. Elsewhere Escape keeps its own meaning (on the map or a
 * vessel's button it ends placing or drawing) and the question, with the run it may hold, stays. */
function confirmHasKeyboard() {
  const at = document.activeElement;
  if (!at || at === document.body || $("save-confirm").contains(at)) return true;
  return ["file-name", "save", "run-frames", "run"].includes(at.id);
}
/** Applies what is being typed into the focused box (its change event comes on leaving it) before Ctrl+S saves: the
 * scenario was saved without it, said "saved" and showed no unsaved mark, while the box showed the text. The box
 * keeps the keyboard. */
function commitTyping() {
  const at = document.activeElement;
  if (!at || !["INPUT", "TEXTAREA", "SELECT"].includes(at.tagName)) return;
  at.blur(); // the browser sends its change event (once, as on leaving the box)
  if (at.isConnected) at.focus();
}
$("undo").addEventListener("click", () => state.undo());
$("redo").addEventListener("click", () => state.redo());
$("preview").addEventListener("click", preview);
$("preview-close").addEventListener("click", closePreview);
// While the preview is open it has the keyboard: Escape closes it, Tab and Shift+Tab go round its own controls.
// (on the window, first: the focus may be on the page's body after a click on the image)
window.addEventListener("keydown", (ev) => {
  if ($("preview-modal").hidden) return;
  if (ev.key === "Escape") {
    ev.preventDefault();
    ev.stopPropagation();
    closePreview();
  } else if (ev.key === "Tab") {
    const stops = previewStops();
    if (!stops.length) return;
    const at = stops.indexOf(document.activeElement);
    const next = ev.shiftKey ? (at <= 0 ? stops.length - 1 : at - 1) : (at + 1) % stops.length;
    ev.preventDefault();
    stops[next].focus();
  }
}, { capture: true });
// a focus that lands outside while it is open (a click on the dimmed page) goes back in
document.addEventListener("focusin", (ev) => {
  if (!$("preview-modal").hidden && !$("preview-modal").contains(ev.target)) previewStops()[0]?.focus();
});
$("preview-modal").addEventListener("click", (ev) => {
  if (ev.target === $("preview-modal")) closePreview(); // a click on the dimmed page around the window
});
$("run").addEventListener("click", run);
$("run-stop").addEventListener("click", async () => {
  if (currentRun) showRun(await api.stopRun(currentRun.id));
});
$("frame").addEventListener("input", (ev) => state.setFrame(Number(ev.target.value)));
$("play").addEventListener("click", togglePlay);
$("fit").addEventListener("click", () => map.fitScenario());
$("fit-map").addEventListener("click", () => map.fitMap());
$("zoom-in").addEventListener("click", () => map.zoomAt(1.5, map.size().w / 2, map.size().h / 2));
$("zoom-out").addEventListener("click", () => map.zoomAt(1 / 1.5, map.size().w / 2, map.size().h / 2));
$("drawing-done").addEventListener("click", () => map.setMode("select"));
window.addEventListener("keydown", (ev) => {
  const typing = ["INPUT", "TEXTAREA", "SELECT"].includes(document.activeElement?.tagName);
  if ((ev.ctrlKey || ev.metaKey) && ev.key.toLowerCase() === "s") {
    ev.preventDefault();
    runAfterSave = null;
    commitTyping();
    save(false);
  } else if (ev.key === "Escape" && !$("save-confirm").hidden && confirmHasKeyboard()) {
    ev.preventDefault();
    const inside = $("save-confirm").contains(document.activeElement) || document.activeElement === $("save");
    cancelConfirm();
    if (inside) $("file-name").focus();
  } else if (!typing && (ev.ctrlKey || ev.metaKey) && ev.key.toLowerCase() === "z") {
    ev.preventDefault();
    if (ev.shiftKey) state.redo();
    else state.undo();
  } else if (!typing && (ev.key === "Enter" || ev.key === "Escape") && map.mode !== "select") {
    map.setMode("select");
  }
});
window.addEventListener("beforeunload", (ev) => {
  commitTyping(); // what is being typed in a box counts as unsaved: it was lost without a question
  if (state.dirty) ev.preventDefault();
});

async function boot() {
  try {
    const [info, bundledList] = await Promise.all([api.info(), api.bundled()]);
    bundled = bundledList;
    panels.init(info.choices, [], null); // the library comes with the scenario opened below (show)
    await refreshOpen();
    // a page loaded again opens the scenario it had open (the address names it), else the one of the command line
    let asked = "";
    try {
      asked = decodeURIComponent(location.hash.slice(1));
    } catch {
      // an address typed by hand that is not percent-encoded text: open what the command line says
    }
    let opened = false;
    if (/^(file|bundled):./.test(asked)) {
      try {
        await load(asked);
        opened = true;
      } catch (err) {
        bootNote = `cannot open ${asked.slice(asked.indexOf(":") + 1)} again: ${err.message}`;
        status(bootNote, true);
      }
    }
    if (!opened && info.initial) {
      await show({
        document: info.initial.document,
        comment: info.initial.comment,
        comments: info.initial.comments,
        name: info.initial.name,
        savedName: info.initial.in_folder ? info.initial.name : null,
      });
      savedEtag = info.initial.in_folder ? info.initial.etag : null;
      if (info.initial.new) {
        newNote = `new scenario: ${info.initial.name} does not exist yet; place vessels from the library, then Save creates it`;
        status(newNote);
      }
    } else if (!opened) {
      const first = bundled.find((b) => b.name === "port_entry") || bundled[0];
      const res = await api.bundledOne(first.name);
      await show({ document: res.document, comment: res.comment, comments: res.comments, name: res.name });
    }
    if (!opened) remember();
    map.applyView();
    await showLastRun();
    document.body.dataset.ready = "1";
  } catch (err) {
    status(`cannot start: ${err.message}`, true);
  }
}

window.mmusvEditor = { state, map, api };
boot();
