// REST calls. Every 401 goes to the login view through onUnauthorized. Error messages
// tell the board's error and alarm numbers in words (words.js).

import { errorText } from "./words.js";

export class ApiError extends Error {
  constructor(status, detail) {
    super(errorText(describeDetail(status, detail)));
    this.status = status;
    this.detail = detail;
  }
}

function describeDetail(status, detail) {
  if (typeof detail === "string") return detail;
  if (detail && Array.isArray(detail.errors)) {
    const shown = detail.errors.slice(0, 3).map((e) => (e.line ? `line ${e.line}: ` : "") + e.message);
    const more = detail.errors.length - shown.length;
    return shown.join("; ") + (more > 0 ? ` (and ${more} more)` : "");
  }
  if (Array.isArray(detail)) {
    // FastAPI request-validation errors
    return detail.map((d) => `${(d.loc || []).join(".")}: ${d.msg}`).join("; ");
  }
  if (detail && typeof detail.message === "string") return detail.message;
  return `request failed (HTTP ${status})`;
}

let onUnauthorized = () => {};
export function setUnauthorizedHandler(fn) {
  onUnauthorized = fn;
}

async function request(method, path, body, headers = {}) {
  // X-Plotbridge: a header no form or no-cors fetch from another origin can send (CSRF).
  const init = { method, credentials: "same-origin", headers: { ...headers, "X-Plotbridge": "1" } };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (err) {
    throw new ApiError(0, `cannot reach the server (${err.message})`);
  }
  if (response.status === 401 && path !== "/api/login") onUnauthorized();
  const text = await response.text();
  let data = null;
  if (text) {
    try {
      data = JSON.parse(text);
    } catch {
      data = text;
    }
  }
  if (!response.ok) throw new ApiError(response.status, data && data.detail !== undefined ? data.detail : data);
  return data;
}

export const api = {
  get: (path) => request("GET", path),
  post: (path, body, headers) => request("POST", path, body ?? {}, headers),
  put: (path, body) => request("PUT", path, body),
  patch: (path, body) => request("PATCH", path, body),
  del: (path) => request("DELETE", path),
};

/**
 * Multipart upload with progress (fetch has no upload progress in all browsers).
 * Resolves with the job; rejects with ApiError (detail.errors for 422).
 */
export function uploadJob(formData, onProgress) {
  return new Promise((resolve, reject) => {
    const xhr = new XMLHttpRequest();
    xhr.open("POST", "/api/jobs");
    xhr.withCredentials = true;
    xhr.setRequestHeader("X-Plotbridge", "1");
    xhr.upload.addEventListener("progress", (e) => {
      if (e.lengthComputable) onProgress(e.loaded, e.total);
    });
    xhr.addEventListener("load", () => {
      let data = null;
      try {
        data = JSON.parse(xhr.responseText);
      } catch {
        data = xhr.responseText;
      }
      if (xhr.status === 401) onUnauthorized();
      if (xhr.status >= 200 && xhr.status < 300) resolve(data);
      else reject(new ApiError(xhr.status, data && data.detail !== undefined ? data.detail : data));
    });
    xhr.addEventListener("error", () => reject(new ApiError(0, "cannot reach the server")));
    xhr.addEventListener("abort", () => reject(new ApiError(0, "upload aborted")));
    xhr.send(formData);
  });
}
