// The tile loader's worker: fetches a batch of tiles (POST {"keys": [[p, l, x, y], ...]} to the
// server's batch endpoint, docs/serve-protocol.md) and splits the response into one
// transferable buffer per tile, off the main thread. Tiles are raw sRGB8 RGB bytes
// (tile_size^2 * 3 each), uploaded as they are: there is nothing else to decode.
// Message in: {id, url, keys, indices, tileBytes}; out: {id, tiles: [{index, bytes}]} or
// {id, error}.

self.onmessage = async (event) => {
  const { id, url, keys, indices, tileBytes } = event.data;
  try {
    const response = await fetch(url, {
      method: "POST",
      headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ keys }),
    });
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
    const body = await response.arrayBuffer();
    if (body.byteLength !== keys.length * tileBytes)
      throw new Error(`${url}: ${body.byteLength} bytes for ${keys.length} tiles of ${tileBytes}`);
    const tiles = indices.map((index, k) => ({ index, bytes: body.slice(k * tileBytes, (k + 1) * tileBytes) }));
    self.postMessage({ id, tiles }, tiles.map((t) => t.bytes));
  } catch (e) {
    self.postMessage({ id, error: String(e && e.message ? e.message : e) });
  }
};
