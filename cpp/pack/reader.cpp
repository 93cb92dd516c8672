#include "pack/reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "common/checksum.h"
#include "common/error.h"
#include "pack/tile_key.h"
#include "pack/bc1.h"

namespace gigascroll {
namespace {

std::string key_text(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
    std::ostringstream s;
    s << "(painting " << p << ", level " << l << ", tile " << tx << ", " << ty << ")";
    return s.str();
}

// Reads exactly n bytes at offset; false on a short read (truncated file).
bool pread_all(int fd, void* out, std::size_t n, std::uint64_t offset) {
    auto* dst = static_cast<std::uint8_t*>(out);
    while (n > 0) {
        const ssize_t r = ::pread(fd, dst, n, static_cast<off_t>(offset));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        dst += r;
        n -= static_cast<std::size_t>(r);
        offset += static_cast<std::uint64_t>(r);
    }
    return true;
}

void check_header(const FileHeader& h, const char (&magic)[8], std::uint32_t version,
                  const std::string& path) {
    if (std::memcmp(h.magic, magic, 8) != 0)
        throw IoError(path + ": not a gigascroll pack file (wrong magic)");
    if (h.version != version)
        throw IoError(path + ": unsupported pack version " + std::to_string(h.version) +
                      " (the manifest says version " + std::to_string(version) + ")");
}

// Thread-local zstd context: no state is shared between loader threads.
ZSTD_DCtx* thread_dctx() {
    struct Holder {
        ZSTD_DCtx* ctx = ZSTD_createDCtx();
        ~Holder() { ZSTD_freeDCtx(ctx); }
    };
    thread_local Holder holder;
    return holder.ctx;
}

}  // namespace

// One tile file: its size, identity and descriptor. Files past the open budget are
// opened on first use (and checked to be the file validated on open).
struct TilePack::TileFile {
    std::string path;
    std::uint64_t size = 0;
    dev_t dev = 0;
    ino_t ino = 0;
    mutable std::atomic<int> fd{-1};
};

namespace {
// Descriptors kept open from construction; a pack of thousands of paintings opens the rest
// on demand rather than exhausting the process's descriptor limit.
constexpr std::size_t kOpenFileBudget = 64;
// Descriptors cached at most (those kept from construction included).
constexpr std::size_t kMaxCachedFiles = 512;
}  // namespace

TilePack::TilePack(const std::string& directory) : directory_(directory) {
    const Manifest m = read_manifest(directory + "/" + kManifestName, &manifest_json_);
    version_ = m.version;
    tile_size_ = m.tile_size;
    border_ = m.border;
    codec_ = m.codec;
    table_width_ = m.table_width;
    table_height_ = m.table_height;
    paintings_ = m.paintings;
    entry_count_ = m.tile_count;
    tile_files_ = m.tile_files;
    if (version_ < 2)
        warnings_.push_back(directory + ": a version-1 pack: its checksums do not name their "
                            "tiles, so swapped or duplicated index entries cannot be detected "
                            "(rebuild it to get version 2)");
    if (codec_ == Codec::Bc1 && (tile_size_ % 4 != 0 || payload() % 4 != 0))
        throw IoError(directory + "/" + kManifestName + ": a bc1 pack needs tile_size and payload "
                      "that are multiples of 4");

    // Index: map it whole; entries are read-only afterwards.
    const std::string index_path = directory + "/" + kIndexName;
    require_regular_file(index_path);
    const int ifd = ::open(index_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (ifd < 0) throw IoError(index_path + ": cannot open: " + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{ifd};
    struct stat st {};
    ::fstat(ifd, &st);
    const auto index_size = static_cast<std::uint64_t>(st.st_size);
    FileHeader h{};
    if (index_size < sizeof(FileHeader) || !pread_all(ifd, &h, sizeof h, 0))
        throw IoError(index_path + ": truncated index");
    check_header(h, kIndexMagic, version_, index_path);
    // 64-bit and division-free: a hostile count cannot wrap count * 24 into a match.
    const std::uint64_t body = index_size - sizeof(FileHeader);
    if (h.entry_size != sizeof(TileEntry) || h.count != entry_count_ ||
        body % sizeof(TileEntry) != 0 || body / sizeof(TileEntry) != entry_count_ ||
        h.data_bytes != body) {
        throw IoError(index_path + ": truncated or inconsistent index (" +
                      std::to_string(index_size) + " bytes for " + std::to_string(entry_count_) +
                      " tiles)");
    }
    index_map_size_ = static_cast<std::size_t>(index_size);
    index_map_ = ::mmap(nullptr, index_map_size_, PROT_READ, MAP_PRIVATE, ifd, 0);
    if (index_map_ == MAP_FAILED) {
        index_map_ = nullptr;
        throw IoError(index_path + ": cannot map: " + std::strerror(errno));
    }
    entries_ = reinterpret_cast<const TileEntry*>(static_cast<const char*>(index_map_) +
                                                  sizeof(FileHeader));

    // Tile files: each one's header and size now; keep a descriptor for pread.
    files_ = std::make_unique<TileFile[]>(tile_files_.size());
    try {
        std::uint64_t tiles = 0, bytes = 0;
        for (std::size_t i = 0; i < tile_files_.size(); ++i) {
            TileFile& f = files_[i];
            f.path = directory + "/" + tile_files_[i];
            require_regular_file(f.path);
            const int fd = ::open(f.path.c_str(), O_RDONLY | O_CLOEXEC);
            if (fd < 0) throw IoError(f.path + ": cannot open: " + std::strerror(errno));
            f.fd.store(fd);
            ::fstat(fd, &st);
            f.size = static_cast<std::uint64_t>(st.st_size);
            f.dev = st.st_dev;
            f.ino = st.st_ino;
            FileHeader th{};
            if (f.size < sizeof(FileHeader) || !pread_all(fd, &th, sizeof th, 0))
                throw IoError(f.path + ": truncated tile data");
            check_header(th, kTilesMagic, version_, f.path);
            if (th.data_bytes != f.size - sizeof(FileHeader) || th.count > entry_count_)
                throw IoError(f.path + ": truncated tile data (" + std::to_string(f.size) +
                              " bytes, header promises " +
                              std::to_string(sizeof(FileHeader) + th.data_bytes) + ")");
            tiles += th.count;
            bytes += f.size;
            if (i >= kOpenFileBudget) {
                ::close(fd);
                f.fd.store(-1);
            } else {
                cached_fds_.fetch_add(1, std::memory_order_relaxed);
            }
        }
        if (tiles != entry_count_)
            throw IoError(directory + ": the tile files hold " + std::to_string(tiles) +
                          " tiles, the manifest " + std::to_string(entry_count_));
        if ((version_ >= 2 || m.tiles_bytes != 0) && bytes != m.tiles_bytes)
            throw IoError(directory + ": the tile files hold " + std::to_string(bytes) +
                          " bytes, the manifest's tiles_bytes says " + std::to_string(m.tiles_bytes));
    } catch (...) {
        release();  // the destructor does not run when the constructor throws
        throw;
    }
}

TilePack::~TilePack() { release(); }

int TilePack::file_descriptor(std::uint32_t file, bool& transient) const {
    TileFile& f = files_[file];
    transient = false;
    int fd = f.fd.load(std::memory_order_acquire);
    if (fd >= 0) return fd;
    fd = ::open(f.path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw IoError(f.path + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || st.st_dev != f.dev || st.st_ino != f.ino ||
        std::uint64_t(st.st_size) != f.size) {
        ::close(fd);
        throw IoError(f.path + ": replaced or resized since the pack was opened");
    }
    // Past the cache budget (a pack of thousands of paintings), read through a descriptor of
    // its own that the caller closes, rather than exhausting the process's descriptors.
    if (cached_fds_.fetch_add(1, std::memory_order_relaxed) >= kMaxCachedFiles) {
        cached_fds_.fetch_sub(1, std::memory_order_relaxed);
        transient = true;
        return fd;
    }
    int expected = -1;
    if (!f.fd.compare_exchange_strong(expected, fd, std::memory_order_acq_rel)) {
        ::close(fd);  // another thread opened it first
        cached_fds_.fetch_sub(1, std::memory_order_relaxed);
        return expected;
    }
    return fd;
}

PackGeometry TilePack::geometry() const {
    PackGeometry g;
    g.tile_size = tile_size_;
    g.border = border_;
    g.table_width = table_width_;
    g.table_height = table_height_;
    for (const PaintingInfo& p : paintings_) g.paintings.push_back(p.geometry);
    return g;
}

void TilePack::release() {
    if (index_map_) ::munmap(index_map_, index_map_size_);
    index_map_ = nullptr;
    if (files_)
        for (std::size_t i = 0; i < tile_files_.size(); ++i) {
            const int fd = files_[i].fd.exchange(-1);
            if (fd >= 0) ::close(fd);
        }
}

TileEntry TilePack::entry(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                          std::uint32_t ty) const {
    if (!has_tile(p, l, tx, ty))
        throw InvalidArgument("tile " + key_text(p, l, tx, ty) +
                              " is not stored (padding outside the painting)");
    const PaintingGeometry& g = paintings_[p].geometry;
    TileEntry e;
    std::memcpy(&e, &entries_[g.first_entry() + g.tile_index(l, tx, ty)], sizeof e);
    if (e.flags != kTileStored || (version_ < 2 && e.file != 0)) {
        const std::uint32_t flags = version_ < 2 ? (std::uint32_t(e.file) << 16 | e.flags) : e.flags;
        char hex[16];
        std::snprintf(hex, sizeof hex, "0x%x", flags);
        throw IoError(directory_ + ": index entry of tile " + key_text(p, l, tx, ty) +
                      " has flags " + hex + " (a finished pack stores only 1 = stored)");
    }
    if (e.file >= tile_files_.size())
        throw IoError(directory_ + ": index entry of tile " + key_text(p, l, tx, ty) +
                      " names tile file " + std::to_string(e.file) + " of " +
                      std::to_string(tile_files_.size()));
    const std::uint64_t size = files_[e.file].size;
    if (e.offset < sizeof(FileHeader) || e.offset > size || e.length > size - e.offset)
        throw IoError(directory_ + ": index entry of tile " + key_text(p, l, tx, ty) +
                      " points outside " + tile_files_[e.file]);
    return e;
}

bool TilePack::has_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                        std::uint32_t ty) const {
    if (p >= paintings_.size())
        throw InvalidArgument("painting " + std::to_string(p) + " out of range (pack has " +
                              std::to_string(paintings_.size()) + ")");
    const PaintingGeometry& g = paintings_[p].geometry;
    if (l >= g.levels())
        throw InvalidArgument("level " + std::to_string(l) + " out of range (painting " +
                              std::to_string(p) + " has " + std::to_string(g.levels()) + ")");
    const std::uint32_t gw = std::max(1u, g.page_table_width() >> l),
                        gh = std::max(1u, g.page_table_height() >> l);
    if (tx >= gw || ty >= gh)
        throw InvalidArgument("tile " + key_text(p, l, tx, ty) + " outside the level's " +
                              std::to_string(gw) + " x " + std::to_string(gh) + " page-table grid");
    return tx < g.tiles_x(l) && ty < g.tiles_y(l);
}

TileLocation TilePack::locate(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                              std::uint32_t ty) const {
    const TileEntry e = entry(p, l, tx, ty);
    return {e.offset, e.length, e.checksum, e.file};
}

// A tile file's descriptor for one read: the cached one, or (past the cache budget) one of its
// own, closed when the read is done.
struct TilePack::FileHandle {
    FileHandle(const TilePack& pack, std::uint32_t file) : fd(pack.file_descriptor(file, transient)) {}
    ~FileHandle() {
        if (transient) ::close(fd);
    }
    FileHandle(const FileHandle&) = delete;
    FileHandle& operator=(const FileHandle&) = delete;
    bool transient = false;
    int fd;
};

void TilePack::read_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty,
                         std::uint8_t* out) const {
    const TileEntry e = entry(p, l, tx, ty);
    const std::size_t bytes = tile_bytes();
    if (codec_ == Codec::Raw) {
        const FileHandle file(*this, e.file);
        const int fd = file.fd;
        // An instance's tiles are its source's: their checksums name the source's tiles.
        const std::uint64_t key = TileKey{tile_source(paintings_, p), l, tx, ty}.packed();
        if (e.length != bytes)
            throw IoError(directory_ + ": tile " + key_text(p, l, tx, ty) + " has length " +
                          std::to_string(e.length) + ", expected " + std::to_string(bytes));
        if (!pread_all(fd, out, bytes, e.offset))
            throw IoError(directory_ + ": short read of tile " + key_text(p, l, tx, ty));
        if (tile_checksum(version_, key, out, bytes) != e.checksum)
            throw IoError(directory_ + ": checksum mismatch in tile " + key_text(p, l, tx, ty));
        return;
    }
    thread_local std::vector<std::uint8_t> scratch;
    scratch.resize(e.length);
    const std::uint8_t* stored = read_stored(e, p, l, tx, ty, scratch.data());
    if (codec_ == Codec::Bc1) {
        bc1_decode_tile(stored, tile_size_, out);
        return;
    }
    const std::size_t n = ZSTD_decompressDCtx(thread_dctx(), out, bytes, stored, e.length);
    if (ZSTD_isError(n) || n != bytes)
        throw IoError(directory_ + ": corrupt zstd data in tile " + key_text(p, l, tx, ty));
}

const std::uint8_t* TilePack::read_stored(const TileEntry& e, std::uint32_t p, std::uint32_t l,
                                          std::uint32_t tx, std::uint32_t ty,
                                          std::uint8_t* into) const {
    // entry() has checked that e lies inside its tile file.
    if (codec_ == Codec::Bc1 && e.length != bc1_tile_bytes(tile_size_))
        throw IoError(directory_ + ": bc1 tile " + key_text(p, l, tx, ty) + " has length " +
                      std::to_string(e.length) + ", expected " +
                      std::to_string(bc1_tile_bytes(tile_size_)));
    const FileHandle file(*this, e.file);
    if (!pread_all(file.fd, into, e.length, e.offset))
        throw IoError(directory_ + ": short read of tile " + key_text(p, l, tx, ty));
    const std::uint64_t key = TileKey{tile_source(paintings_, p), l, tx, ty}.packed();
    if (tile_checksum(version_, key, into, e.length) != e.checksum)
        throw IoError(directory_ + ": checksum mismatch in tile " + key_text(p, l, tx, ty));
    return into;
}

void TilePack::read_slot_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                              std::uint32_t ty, std::uint8_t* out) const {
    if (codec_ != Codec::Bc1) {
        read_tile(p, l, tx, ty, out);
        return;
    }
    // Straight into the caller's buffer: the blocks are what the cache keeps.
    read_stored(entry(p, l, tx, ty), p, l, tx, ty, out);
}

}  // namespace gigascroll
