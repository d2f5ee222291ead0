// The editor's state: the scenario document (the JSON form of the YAML file), the last evaluation by the server,
// the selection, the current acquisition index and the undo history. Views subscribe with on(event, fn).

import { api } from "./api.js";

const HISTORY = 100;

/** A canonical text of a value: JSON with the keys of every object in sorted order, so two documents that hold the
 * same scenario give the same text whatever order their keys were written in. */
export function canonical(value) {
  return JSON.stringify(value, (key, v) =>
    v && typeof v === "object" && !Array.isArray(v) ? Object.fromEntries(Object.keys(v).sort().map((k) => [k, v[k]])) : v,
  );
}

export class EditorState {
  constructor() {
    this.doc = null; // scenario document, as /api/evaluate and the YAML file know it
    this.comment = "";
    this.comments = []; // the file's other comments with their anchors, sent back on save (the page edits none; a
    // renamed vessel's follow it)
    this.fileName = "";
    this.savedName = null; // the folder file this document was loaded from or saved to
    this.savedKey = null; // canonical text of the scenario (document and comment) last opened or saved
    this.evaluation = null; // last answer of /api/evaluate for the current document (null while pending)
    this.lastGood = null; // last evaluation that had motion (valid schema), for drawing while one is pending
    this.selected = null; // vessel id
    this.frame = 0;
    this.framePoses = null; // [[x, y, yaw], ...] at this.frame when the evaluation has no bulk poses
    this.mapKey = null;
    this.mapLayers = null;
    this.assets = [];
    this.choices = null;
    this.undoStack = [];
    this.redoStack = [];
    this.listeners = {};
    this.seq = 0; // evaluation requests sent
    this.inFlight = false;
    this.queued = false;
    this.evalError = null;
  }

  /** Canonical text of the scenario as it is now (its document and its comment, which the file holds too). */
  key() {
    return canonical({ document: this.doc, comment: this.comment });
  }

  /** Whether the scenario differs from the one last opened or saved (undoing back to it makes it clean again). */
  get dirty() {
    return this.doc !== null && this.key() !== this.savedKey;
  }

  /** Marks `key` (the scenario's key() when it was sent to be saved) as the scenario the file now holds. */
  markSaved(key) {
    this.savedKey = key;
  }

  on(event, fn) {
    (this.listeners[event] ||= []).push(fn);
  }

  emit(event, arg) {
    for (const fn of this.listeners[event] || []) fn(arg);
  }

  vessel(id = this.selected) {
    return this.doc?.vessels?.find((v) => v.id === id) || null;
  }

  vesselIndex(id) {
    return this.doc?.vessels?.findIndex((v) => v.id === id) ?? -1;
  }

  /** Replaces the whole document (opening a file): clears the history. */
  load({ document, comment, comments, name, savedName }) {
    this.doc = structuredClone(document);
    this.comment = comment || "";
    this.comments = comments || [];
    this.fileName = name || "";
    this.savedName = savedName || null;
    this.savedKey = this.key();
    this.undoStack = [];
    this.redoStack = [];
    this.selected = null;
    this.frame = 0;
    this.evaluation = null;
    this.lastGood = null;
    this.emit("loaded");
    this.emit("jump");
    this.changed();
  }

  /** The document, its description (the leading comment) and the other comments as one entry of the undo history
   * (a renamed vessel's comments follow it, and undoing the rename takes them back; an edited description is undone
   * as any edit: without it, Undo left the description and took back the edit before it). */
  snapshot() {
    return JSON.stringify({ doc: this.doc, comment: this.comment, comments: this.comments });
  }

  restore(entry) {
    const { doc, comment, comments } = JSON.parse(entry);
    this.doc = doc;
    this.comment = comment;
    this.comments = comments;
  }

  /** Applies fn(doc) as one undoable edit. `live` edits (a drag in progress) push history once per gesture. */
  edit(fn, { gesture = null } = {}) {
    if (!this.doc) return;
    if (gesture === null || gesture !== this.lastGesture) {
      this.undoStack.push(this.snapshot());
      if (this.undoStack.length > HISTORY) this.undoStack.shift();
      this.redoStack = [];
    }
    this.lastGesture = gesture;
    fn(this.doc);
    this.changed();
  }

  /** Renames vessel `from` to `to` as one undoable edit; the file's comments anchored at that vessel follow it (the
   * server matches a vessel's comments by its id). */
  renameVessel(from, to) {
    const i = this.vesselIndex(from);
    if (i < 0) return;
    this.edit((doc) => {
      doc.vessels[i].id = to;
      this.comments = this.comments.map((c) =>
        c.path.length >= 2 && c.path[0] === "vessels" && c.path[1] === from ? { ...c, path: ["vessels", to, ...c.path.slice(2)] } : c,
      );
    });
  }

  undo() {
    if (!this.undoStack.length) return;
    this.redoStack.push(this.snapshot());
    this.restore(this.undoStack.pop());
    this.lastGesture = null;
    if (this.selected && !this.vessel()) this.selected = null;
    this.emit("jump");
    this.changed();
  }

  redo() {
    if (!this.redoStack.length) return;
    this.undoStack.push(this.snapshot());
    this.restore(this.redoStack.pop());
    this.lastGesture = null;
    if (this.selected && !this.vessel()) this.selected = null;
    this.emit("jump");
    this.changed();
  }

  select(id) {
    this.selected = id;
    this.emit("selection");
  }

  setFrame(k) {
    this.frame = k;
    this.framePoses = null;
    this.emit("frame");
    this.fetchFramePoses();
  }

  /** Poses at the current frame: from the evaluation's bulk poses, or fetched one index at a time. */
  posesAt(k = this.frame) {
    const ev = this.evaluation?.valid ? this.evaluation : null;
    if (!ev) return null;
    if (ev.vessels.length && ev.vessels[0].poses) {
      return ev.vessels.map((v) => v.poses[Math.min(k, v.poses.length - 1)]);
    }
    return this.framePoses;
  }

  async fetchFramePoses() {
    const ev = this.evaluation;
    if (!ev?.valid || !ev.vessels.length || ev.vessels[0].poses) return;
    const k = this.frame;
    try {
      const res = await api.poses(this.doc, k);
      if (this.frame === k && this.evaluation === ev) {
        this.framePoses = res.poses;
        this.emit("frame");
      }
    } catch (err) {
      this.emit("status", { text: err.message, error: true });
    }
  }

  changed() {
    this.evaluation = null;
    this.emit("doc");
    this.requestEvaluation();
  }

  pending() {
    return this.inFlight || this.queued;
  }

  /** One evaluation in flight at a time; edits made meanwhile are evaluated once it returns (latest wins). */
  requestEvaluation() {
    if (this.inFlight) {
      this.queued = true;
      document.body.dataset.pending = "1";
      return;
    }
    this.runEvaluation();
  }

  async runEvaluation() {
    this.inFlight = true;
    this.queued = false;
    document.body.dataset.pending = "1";
    const sent = JSON.stringify(this.doc);
    const seq = ++this.seq;
    let result = null;
    try {
      result = await api.evaluate(JSON.parse(sent));
      this.evalError = null;
    } catch (err) {
      this.evalError = err.message;
    }
    this.inFlight = false;
    if (this.queued || JSON.stringify(this.doc) !== sent) {
      this.runEvaluation();
      return;
    }
    this.evaluation = result;
    if (result?.valid) {
      this.lastGood = result;
      const last = Math.max(0, (result.frames || 1) - 1);
      if (this.frame > last) this.frame = last;
    }
    document.body.dataset.pending = "0";
    document.body.dataset.evaluations = String(seq);
    this.emit("evaluated");
    this.fetchFramePoses();
  }
}
