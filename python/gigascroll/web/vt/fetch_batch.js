// One batch of tiles from the server (POST {"keys": [[p, l, x, y], ...]} to the batch endpoint,
// docs/serve-protocol.md), split into one transferable buffer per tile. Used by the loader's
// worker and, where no Worker exists, by the loader itself. A 429 (every tile slot of the
// server busy) is asked again after its Retry-After (at most MAX_TRIES times in all): the
// coarse tail a page needs before it draws is then late, not a failed page.
// In: {id, url, keys, indices, tileBytes}; out: {id, tiles: [{index, bytes}]} or {id, error}.

export const MAX_TRIES = 6;
const MAX_WAIT_MS = 5000;

export async function fetchBatch({ id, url, keys, indices, tileBytes }, sleep = defaultSleep) {
  try {
    let response;
    for (let attempt = 1; ; attempt++) {
      response = await fetch(url, { method: "POST", headers: { "Content-Type": "application/json" },
                                    body: JSON.stringify({ keys }) });
      if (response.status !== 429 || attempt >= MAX_TRIES) break;
      await sleep(retryAfterMs(response.headers.get("Retry-After"), attempt));
    }
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
    const body = await response.arrayBuffer();
    if (body.byteLength !== keys.length * tileBytes)
      throw new Error(`${url}: ${body.byteLength} bytes for ${keys.length} tiles of ${tileBytes}`);
    return { id, tiles: indices.map((index, k) => ({ index, bytes: body.slice(k * tileBytes, (k + 1) * tileBytes) })) };
  } catch (e) {
    return { id, error: String(e && e.message ? e.message : e) };
  }
}

// Milliseconds to wait before the next try: the server's Retry-After seconds, else 250 ms
// doubled each try; at most MAX_WAIT_MS.
export function retryAfterMs(header, attempt) {
  const seconds = Number(header);
  const ms = header !== null && header !== "" && Number.isFinite(seconds) && seconds >= 0
    ? seconds * 1000 : 250 * 2 ** (attempt - 1);
  return Math.min(ms, MAX_WAIT_MS);
}

function defaultSleep(ms) {
  return new Promise((resolve) => setTimeout(resolve, ms));
}
