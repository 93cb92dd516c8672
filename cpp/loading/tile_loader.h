// Asynchronous tile loading (VT-mobile-VR §4.2). The main thread submits load commands and, once
// per frame, polls the finished tiles; loader threads read, decompress and verify tiles from
// the pack into buffers of a preallocated pool.
//
//   LockFree (the seed's design): one SPSC command queue per loader thread (the main thread
//   deals commands round-robin), one MPSC result queue back, and per thread an SPSC queue of
//   free buffers returned by the main thread. Idle threads sleep in std::atomic::wait on a
//   per-thread wake counter (libstdc++ polls a few dozen times, then sleeps on a futex), so
//   an idle thread costs no CPU; the main thread never blocks.
//   Locked (the Unreal-style baseline): N workers sharing mutex + condition-variable job,
//   free-buffer and result queues.
//
// Back-pressure, not dropping: commands that do not fit in the queues wait in a main-thread
// backlog that every submit() and poll() flushes; a thread without a free buffer or with a
// full result queue waits. A failed read (short file, checksum, corrupt zstd frame) becomes
// an error result for that tile and the thread carries on. close() stops the threads without
// waiting for queued commands (they are dropped and counted); tiles that finished before stay
// pollable, including one a thread could not hand over because the result queue was full.
//
// Thread safety: the seed's design has one main thread, but Python code may call a loader
// from several threads. Every public call takes one mutex, so calls from several threads
// are serialised (uncontended in the one-main-thread design, next to microseconds per tile): each
// tile is delivered exactly once, to one poll(), and close() from any thread is safe.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pack/geometry.h"
#include "pack/tile_key.h"

namespace gigascroll {

class TilePack;

// Identifies an opened pack (never 0): a hash of its canonical directory and its manifest.
// Two TilePacks opened on the same directory agree; any other pack differs, even one of the
// same geometry, so a cache refuses tiles of a loader that reads another pack.
std::uint64_t pack_fingerprint(const TilePack& pack);

enum class LoaderMode { LockFree, Locked };
// "lockfree" / "locked"; InvalidArgument otherwise.
LoaderMode parse_loader_mode(const std::string& name);
const char* loader_mode_name(LoaderMode mode);

struct LoaderOptions {
    std::size_t queue_capacity = 4096;  // commands queued towards the threads
    std::size_t pool_tiles = 64;        // preallocated tile buffers, shared by the threads
};

struct LoadedTile {
    TileKey key;
    std::int32_t buffer = -1;  // pool buffer holding the tile; -1 when the load failed
    std::string error;         // why it failed
};

struct LoaderStats {
    std::uint64_t submitted = 0, loaded = 0, failed = 0, cancelled = 0;
    std::uint64_t backlog = 0;  // accepted by submit() but not yet in a queue
};

class TileLoader {
public:
    // The pack must outlive the loader. InvalidArgument for threads == 0 or tiny options.
    TileLoader(const TilePack& pack, LoaderMode mode, unsigned threads, const LoaderOptions& options = {});
    ~TileLoader();
    TileLoader(const TileLoader&) = delete;
    TileLoader& operator=(const TileLoader&) = delete;

    // InvalidArgument (nothing queued) if a key is not a tile of the pack.
    void submit(const TileKey* keys, std::size_t n);
    // Appends up to max finished tiles to out. Every result with buffer >= 0 must be given
    // back with release() once its data() has been used.
    std::size_t poll(std::vector<LoadedTile>& out, std::size_t max);
    const std::uint8_t* data(std::int32_t buffer) const;
    void release(std::int32_t buffer);
    // Stops the threads (idempotent); see the header comment for what happens to commands.
    void close();

    LoaderStats stats() const;
    LoaderMode mode() const { return mode_; }
    unsigned threads() const { return threads_; }
    std::size_t tile_bytes() const { return tile_bytes_; }  // TilePack::slot_bytes()
    std::uint32_t tile_size() const;
    bool closed() const { return closed_.load(std::memory_order_acquire); }
    const TilePack& pack() const { return pack_; }
    std::uint64_t pack_fingerprint() const { return fingerprint_; }

    struct Impl;  // the transport of one mode (tile_loader.cpp)

private:
    void flush();

    const TilePack& pack_;
    LoaderMode mode_;
    unsigned threads_;
    std::size_t tile_bytes_;
    std::uint64_t fingerprint_;
    std::unique_ptr<Impl> impl_;
    std::vector<std::uint64_t> backlog_;  // packed keys; [backlog_head_, end) still to queue
    std::size_t backlog_head_ = 0;
    std::vector<LoadedTile> leftovers_;   // collected from the threads at close()
    LoaderStats stats_;
    std::atomic<bool> closed_{false};
    mutable std::mutex mutex_;  // serialises the public calls (see the header comment)
};

}  // namespace gigascroll
