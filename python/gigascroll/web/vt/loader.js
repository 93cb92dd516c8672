// Tile loading (the virtual texturing paper §4.2.2 on the web): commands go out as batch
// requests of at most max_batch keys, at most maxBatchesInFlight at once (a browser keeps
// about six HTTP/1.1 connections a host; one POST per frame's misses avoids queueing behind
// them); a worker fetches and splits them (loader_worker.js); arrived tiles wait in a queue
// that the frame drains within its upload budget.

import { fetchBatch } from "./fetch_batch.js";

export class TileLoader {
  constructor(geometry, tiles, { maxBatchesInFlight = 4, useWorker = true } = {}) {
    this.geometry = geometry;
    this.url = (tiles && tiles.batch) || `/api/tiles/${geometry.hash}/batch`;
    this.maxBatch = Math.max(1, Math.min(64, (tiles && tiles.max_batch) || 64));
    this.maxInFlight = maxBatchesInFlight;
    this.tileBytes = geometry.tileSize * geometry.tileSize * 3;
    this.queue = [];        // flat indices waiting for a batch
    this.batches = new Map();  // id -> indices in flight
    this.arrived = [];      // {index, bytes: Uint8Array}
    this.failed = [];       // {indices, error}
    this.nextId = 1;
    this.bytesReceived = 0;
    this.worker = null;
    if (useWorker && typeof Worker !== "undefined") {
      this.worker = new Worker(new URL("./loader_worker.js", import.meta.url), { type: "module" });
      this.worker.onmessage = (e) => this.receive(e.data);
    }
  }

  get tilesInFlight() {
    let n = this.queue.length;
    for (const b of this.batches.values()) n += b.length;
    return n;
  }

  // Queues flat tile indices and sends what the in-flight bound allows.
  request(indices) {
    for (const i of indices) this.queue.push(i);
    this.pump();
  }

  pump() {
    while (this.queue.length && this.batches.size < this.maxInFlight) {
      const indices = this.queue.splice(0, this.maxBatch);
      const id = this.nextId++;
      this.batches.set(id, indices);
      const message = { id, url: this.url, keys: indices.map((i) => this.geometry.keyOf(i)), indices,
                        tileBytes: this.tileBytes };
      if (this.worker) this.worker.postMessage(message);
      else fetchBatch(message).then((m) => this.receive(m));
    }
  }

  receive(m) {
    const indices = this.batches.get(m.id);
    if (!indices) return;
    this.batches.delete(m.id);
    if (m.error) {
      this.failed.push({ indices, error: m.error });
    } else {
      for (const t of m.tiles) {
        this.arrived.push({ index: t.index, bytes: new Uint8Array(t.bytes) });
        this.bytesReceived += t.bytes.byteLength;
      }
    }
    this.pump();
  }

  // Up to `max` arrived tiles, oldest first.
  take(max) { return this.arrived.splice(0, max); }
  takeFailed() { return this.failed.splice(0); }

  dispose() {
    if (this.worker) this.worker.terminate();
    this.worker = null;
  }
}
