// The tile loader's worker: fetches a batch of tiles (fetch_batch.js) and hands back one
// transferable buffer per tile, off the main thread. Tiles are raw sRGB8 RGB bytes
// (tile_size^2 * 3 each), uploaded as they are: there is nothing else to decode.
// Message in: {id, url, keys, indices, tileBytes}; out: {id, tiles: [{index, bytes}]} or
// {id, error}.

import { fetchBatch } from "./fetch_batch.js";

self.onmessage = async (event) => {
  const result = await fetchBatch(event.data);
  self.postMessage(result, result.tiles ? result.tiles.map((t) => t.bytes) : []);
};
