// The server's JSON API (mmusv/editor/app.py). Every call rejects with an Error whose message is the server's.

export class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

async function call(method, path, body, headers = {}) {
  const init = { method, headers: { ...headers } };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  let res;
  try {
    res = await fetch(path, init);
  } catch (err) {
    throw new ApiError(0, `the editor server does not answer (${err.message}); is mmusv editor still running?`);
  }
  const type = res.headers.get("Content-Type") || "";
  if (!res.ok) {
    let message = `${res.status} ${res.statusText}`;
    if (type.includes("json")) {
      const data = await res.json();
      if (data && data.error) message = data.error;
    }
    throw new ApiError(res.status, message);
  }
  if (type.includes("json")) return res.json();
  return res.blob();
}

export const api = {
  info: () => call("GET", "/api/info"),
  // the library of a scenario whose `assets:` lists `entries`: the built-in assets and those of its own asset files
  assets: (entries = []) => {
    const query = entries.map((e) => `assets=${encodeURIComponent(e)}`).join("&");
    return call("GET", query ? `/api/assets?${query}` : "/api/assets");
  },
  bundled: () => call("GET", "/api/bundled"),
  bundledOne: (name) => call("GET", `/api/bundled/${encodeURIComponent(name)}`),
  files: () => call("GET", "/api/files"),
  readFile: (name) => call("GET", `/api/files/${encodeURIComponent(name)}`),
  // etag: the version this page read or last saved; the server refuses (412) to replace a file changed since
  writeFile: (name, body, etag) =>
    call("PUT", `/api/files/${encodeURIComponent(name)}`, body, etag ? { "If-Match": `"${etag}"` } : {}),
  map: (map) => call("POST", "/api/map", { map }),
  evaluate: (document) => call("POST", "/api/evaluate", { document }),
  poses: (document, frame) => call("POST", "/api/poses", { document, frame }),
  preview: (document, frame, agent) => call("POST", "/api/preview", { document, frame, agent }),
  startRun: (name, frames) => call("POST", "/api/runs", { name, frames }),
  runs: () => call("GET", "/api/runs"),
  run: (id) => call("GET", `/api/runs/${id}`),
  stopRun: (id) => call("DELETE", `/api/runs/${id}`),
};
