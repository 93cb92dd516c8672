#include "loading/tile_loader.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <iterator>
#include <optional>
#include <thread>

#include "common/checksum.h"
#include "common/error.h"
#include "concurrency/locked_queue.h"
#include "concurrency/mpsc_queue.h"
#include "concurrency/spsc_queue.h"
#include "pack/reader.h"

namespace gigascroll {

// What both modes share: the buffer pool and the read of one tile.
struct TileLoader::Impl {
    Impl(const TilePack& pack, std::size_t pool_tiles)
        : pack(pack), tile_bytes(pack.slot_bytes()), pool(pool_tiles * tile_bytes) {}
    virtual ~Impl() = default;
    // Queues up to n packed keys; returns how many were taken. Never blocks in lock-free mode.
    virtual std::size_t push(const std::uint64_t* keys, std::size_t n) = 0;
    virtual std::size_t pop(std::vector<LoadedTile>& out, std::size_t max) = 0;
    virtual void release(std::int32_t buffer) = 0;
    // Stops and joins the threads; finished tiles they still held go to leftovers. Returns
    // the number of commands that were queued but never loaded.
    virtual std::size_t stop(std::vector<LoadedTile>& leftovers) = 0;

    std::uint8_t* buffer(std::int32_t b) { return pool.data() + std::size_t(b) * tile_bytes; }

    // Reads one tile into buffer b in the cache's form (RGB8, or a bc1 pack's blocks as
    // stored); a failure is a result, never an escaping exception.
    LoadedTile load(std::uint64_t packed, std::int32_t b) {
        LoadedTile r;
        r.key = TileKey::unpack(packed);
        try {
            pack.read_slot_tile(r.key.painting, r.key.level, r.key.tx, r.key.ty, buffer(b));
            r.buffer = b;
        } catch (const std::exception& e) {
            r.error = e.what();
        }
        return r;
    }

    const TilePack& pack;
    const std::size_t tile_bytes;
    std::vector<std::uint8_t> pool;  // preallocated: no allocation per tile
};

namespace {

constexpr std::size_t kDeal = 32;  // commands handed to one thread per round-robin turn

class LockFreeLoader final : public TileLoader::Impl {
public:
    LockFreeLoader(const TilePack& pack, unsigned threads, const LoaderOptions& o)
        : Impl(pack, round_pool(o.pool_tiles, threads)),
          per_thread_(round_pool(o.pool_tiles, threads) / threads),
          results_(round_pool(o.pool_tiles, threads) + o.queue_capacity) {
        for (unsigned t = 0; t < threads; ++t)
            workers_.push_back(std::make_unique<Worker>(std::max<std::size_t>(o.queue_capacity / threads, kDeal),
                                                        per_thread_));
        for (unsigned t = 0; t < threads; ++t) {
            Worker& w = *workers_[t];
            for (std::size_t i = 0; i < per_thread_; ++i)
                GS_CHECK(w.free.try_push(std::int32_t(t * per_thread_ + i)));  // sized for them
            w.thread = std::thread([this, &w] { run(w); });
        }
    }

    ~LockFreeLoader() override {
        std::vector<LoadedTile> ignored;
        stop(ignored);
    }

    std::size_t push(const std::uint64_t* keys, std::size_t n) override {
        std::size_t done = 0;
        std::vector<char> fed(workers_.size(), 0);
        for (unsigned misses = 0; done < n && misses < workers_.size();) {
            const unsigned t = next_;
            next_ = (next_ + 1) % workers_.size();
            const std::size_t k = workers_[t]->commands.try_push_batch(keys + done, std::min(kDeal, n - done));
            if (k == 0) {
                ++misses;
                continue;
            }
            done += k;
            misses = 0;
            fed[t] = 1;
        }
        for (std::size_t t = 0; t < workers_.size(); ++t)
            if (fed[t]) wake(*workers_[t]);
        return done;
    }

    std::size_t pop(std::vector<LoadedTile>& out, std::size_t max) override {
        const std::size_t k = results_.try_pop_batch(std::back_inserter(out), max);
        if (k)  // room in the result queue: a thread may be waiting to hand over a tile
            for (auto& w : workers_) wake(*w);
        return k;
    }

    void release(std::int32_t b) override {
        Worker& w = *workers_[std::size_t(b) / per_thread_];
        GS_CHECK(w.free.try_push(b));  // never full: it holds at most the thread's own buffers
        wake(w);
    }

    std::size_t stop(std::vector<LoadedTile>& leftovers) override {
        if (stopped_) return 0;
        stopped_ = true;
        stopping_.store(true, std::memory_order_release);
        for (auto& w : workers_) wake(*w);
        std::size_t unloaded = 0;
        for (auto& w : workers_) {
            w->thread.join();
            if (w->leftover) leftovers.push_back(std::move(*w->leftover));
            unloaded += w->commands.size_approx();  // exact once the consumer has exited
        }
        return unloaded;
    }

private:
    struct Worker {
        Worker(std::size_t commands_capacity, std::size_t buffers)
            : commands(commands_capacity), free(buffers) {}
        SpscQueue<std::uint64_t> commands;  // main -> thread
        SpscQueue<std::int32_t> free;       // main -> thread: buffers given back
        // Bumped (release) by the main thread after it gives the thread something to do.
        alignas(kCacheLine) std::atomic<std::uint32_t> wake{0};
        std::optional<LoadedTile> leftover;  // written by the thread before it exits
        std::thread thread;
    };

    static std::size_t round_pool(std::size_t pool, unsigned threads) {
        return std::max<std::size_t>((pool + threads - 1) / threads, 1) * threads;
    }

    static void wake(Worker& w) {
        w.wake.fetch_add(1, std::memory_order_release);
        w.wake.notify_one();
    }

    // The thread reads its wake counter *before* looking for work and sleeps only while the
    // counter still holds that value. The main thread publishes work (queue release store)
    // and then bumps the counter, so either the thread's checks see the work, or its wait()
    // sees the new counter value and returns at once: no lost wake-up, no spinning.
    void run(Worker& w) {
        std::optional<LoadedTile> pending;
        std::int32_t buf = -1;
        for (;;) {
            const std::uint32_t epoch = w.wake.load(std::memory_order_acquire);
            if (stopping_.load(std::memory_order_acquire)) break;
            if (pending) {
                if (results_.try_push(std::move(*pending))) {  // moves only on success
                    pending.reset();
                    continue;
                }
            } else if (buf >= 0 || w.free.try_pop(buf)) {
                std::uint64_t key;
                if (w.commands.try_pop(key)) {
                    pending = load(key, buf);
                    if (pending->buffer >= 0) buf = -1;  // handed over with the result
                    continue;
                }
            }
            w.wake.wait(epoch, std::memory_order_acquire);
        }
        if (pending && !results_.try_push(std::move(*pending))) w.leftover = std::move(pending);
    }

    const std::size_t per_thread_;
    MpscQueue<LoadedTile> results_;  // threads -> main
    std::vector<std::unique_ptr<Worker>> workers_;
    std::atomic<bool> stopping_{false};
    unsigned next_ = 0;  // round-robin position (main thread only)
    bool stopped_ = false;
};

class LockedLoader final : public TileLoader::Impl {
public:
    LockedLoader(const TilePack& pack, unsigned threads, const LoaderOptions& o)
        : Impl(pack, o.pool_tiles), jobs_(o.queue_capacity), free_(o.pool_tiles),
          results_(o.pool_tiles + o.queue_capacity), leftovers_(threads) {
        for (std::size_t i = 0; i < o.pool_tiles; ++i) GS_CHECK(free_.try_push(std::int32_t(i)));
        for (unsigned t = 0; t < threads; ++t) threads_.emplace_back([this, t] { run(t); });
    }

    ~LockedLoader() override {
        std::vector<LoadedTile> ignored;
        stop(ignored);
    }

    std::size_t push(const std::uint64_t* keys, std::size_t n) override {
        return jobs_.try_push_batch(keys, n);
    }
    std::size_t pop(std::vector<LoadedTile>& out, std::size_t max) override {
        return results_.try_pop_batch(std::back_inserter(out), max);
    }
    void release(std::int32_t b) override { GS_CHECK(free_.try_push(b)); }  // holds the whole pool

    std::size_t stop(std::vector<LoadedTile>& leftovers) override {
        if (stopped_) return 0;
        stopped_ = true;
        stopping_.store(true, std::memory_order_release);
        jobs_.close();
        free_.close();
        results_.close();
        for (auto& t : threads_) t.join();
        for (auto& l : leftovers_)
            if (l) leftovers.push_back(std::move(*l));
        return jobs_.size() + dropped_.load(std::memory_order_relaxed);
    }

private:
    void run(unsigned t) {
        std::uint64_t key;
        while (jobs_.wait_pop(key)) {
            std::int32_t b;
            if (stopping_.load(std::memory_order_acquire) || !free_.wait_pop(b)) {
                dropped_.fetch_add(1, std::memory_order_relaxed);  // popped, never loaded
                break;
            }
            LoadedTile r = load(key, b);
            if (r.buffer < 0) GS_CHECK(free_.try_push(b));
            if (!results_.wait_push(std::move(r))) {  // closed: keep the finished tile
                leftovers_[t] = std::move(r);
                break;
            }
        }
    }

    LockedQueue<std::uint64_t> jobs_;
    LockedQueue<std::int32_t> free_;
    LockedQueue<LoadedTile> results_;
    std::vector<std::optional<LoadedTile>> leftovers_;  // one per thread, read after join
    std::vector<std::thread> threads_;
    std::atomic<bool> stopping_{false};
    std::atomic<std::size_t> dropped_{0};
    bool stopped_ = false;
};

}  // namespace

std::uint64_t pack_fingerprint(const TilePack& pack) {
    std::error_code ec;
    const std::string dir = std::filesystem::weakly_canonical(pack.directory(), ec).string();
    const std::string key = (ec ? pack.directory() : dir) + '\0' + pack.manifest_json();
    return checksum64(key.data(), key.size()) | 1;
}

LoaderMode parse_loader_mode(const std::string& m) {
    if (m == "lockfree") return LoaderMode::LockFree;
    if (m == "locked") return LoaderMode::Locked;
    throw InvalidArgument("mode must be 'lockfree' or 'locked', got '" + m + "'");
}

const char* loader_mode_name(LoaderMode mode) {
    return mode == LoaderMode::LockFree ? "lockfree" : "locked";
}

TileLoader::TileLoader(const TilePack& pack, LoaderMode mode, unsigned threads, const LoaderOptions& o)
    : pack_(pack), mode_(mode), threads_(threads), tile_bytes_(pack.slot_bytes()),
      fingerprint_(gigascroll::pack_fingerprint(pack)) {
    require(threads >= 1 && threads <= 64, "loader threads must be in 1..64");
    require(o.queue_capacity >= 1 && o.pool_tiles >= 1, "queue_capacity and pool_tiles must be positive");
    // Bounds checked before anything is allocated, with what the request would cost.
    constexpr std::size_t kMaxQueue = std::size_t(1) << 24;          // 128 MiB of commands
    constexpr std::size_t kMaxPoolBytes = std::size_t(8) << 30;      // 8 GiB of tile buffers
    require(o.queue_capacity <= kMaxQueue,
            "queue_capacity must be at most 2^24 commands (" + std::to_string(o.queue_capacity) +
                " would need about " + std::to_string(o.queue_capacity / (1u << 20) * 8) + " MiB)");
    require(o.pool_tiles <= kMaxPoolBytes / tile_bytes_,
            "pool_tiles must be at most " + std::to_string(kMaxPoolBytes / tile_bytes_) +
                " (8 GiB of " + std::to_string(tile_bytes_) + "-byte tiles; " +
                std::to_string(o.pool_tiles) + " would need " +
                std::to_string(o.pool_tiles / (1u << 20) * tile_bytes_) + " MiB)");
    if (mode == LoaderMode::LockFree)
        impl_ = std::make_unique<LockFreeLoader>(pack, threads, o);
    else
        impl_ = std::make_unique<LockedLoader>(pack, threads, o);
}

TileLoader::~TileLoader() { close(); }

std::uint32_t TileLoader::tile_size() const { return pack_.tile_size(); }

void TileLoader::submit(const TileKey* keys, std::size_t n) {
    std::lock_guard lock(mutex_);
    require(!closed_, "the loader is closed");
    const auto& ps = pack_.paintings();
    for (std::size_t i = 0; i < n; ++i) {
        const TileKey& k = keys[i];
        require(k.painting < ps.size() && k.level < ps[k.painting].geometry.levels() &&
                    k.tx < ps[k.painting].geometry.tiles_x(k.level) &&
                    k.ty < ps[k.painting].geometry.tiles_y(k.level),
                "tile (" + std::to_string(k.painting) + ", " + std::to_string(k.level) + ", " +
                    std::to_string(k.tx) + ", " + std::to_string(k.ty) + ") is not in the pack");
    }
    if (backlog_head_ == backlog_.size()) {
        backlog_.clear();
        backlog_head_ = 0;
    }
    for (std::size_t i = 0; i < n; ++i) backlog_.push_back(keys[i].packed());
    stats_.submitted += n;
    flush();
}

void TileLoader::flush() {
    if (closed_ || backlog_head_ == backlog_.size()) return;
    backlog_head_ += impl_->push(backlog_.data() + backlog_head_, backlog_.size() - backlog_head_);
    if (backlog_head_ > 4096 && backlog_head_ * 2 > backlog_.size()) {  // compact now and then
        backlog_.erase(backlog_.begin(), backlog_.begin() + std::ptrdiff_t(backlog_head_));
        backlog_head_ = 0;
    }
}

std::size_t TileLoader::poll(std::vector<LoadedTile>& out, std::size_t max) {
    std::lock_guard lock(mutex_);
    const std::size_t before = out.size();
    const std::size_t from_leftovers = std::min(max, leftovers_.size());
    for (std::size_t i = 0; i < from_leftovers; ++i) out.push_back(std::move(leftovers_[i]));
    leftovers_.erase(leftovers_.begin(), leftovers_.begin() + std::ptrdiff_t(from_leftovers));
    impl_->pop(out, max - from_leftovers);
    flush();
    for (std::size_t i = before; i < out.size(); ++i) (out[i].buffer >= 0 ? stats_.loaded : stats_.failed)++;
    return out.size() - before;
}

const std::uint8_t* TileLoader::data(std::int32_t b) const {
    require(b >= 0 && std::size_t(b) * tile_bytes_ < impl_->pool.size(), "invalid tile buffer");
    return impl_->buffer(b);
}

void TileLoader::release(std::int32_t b) {
    require(b >= 0 && std::size_t(b) * tile_bytes_ < impl_->pool.size(), "invalid tile buffer");
    std::lock_guard lock(mutex_);
    if (!closed_) impl_->release(b);
}

void TileLoader::close() {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    closed_.store(true, std::memory_order_release);
    stats_.cancelled = impl_->stop(leftovers_) + (backlog_.size() - backlog_head_);
    backlog_.clear();
    backlog_head_ = 0;
}

LoaderStats TileLoader::stats() const {
    std::lock_guard lock(mutex_);
    LoaderStats s = stats_;
    s.backlog = backlog_.size() - backlog_head_;
    return s;
}

}  // namespace gigascroll
