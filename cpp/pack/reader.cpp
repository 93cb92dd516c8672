#include "pack/reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "common/checksum.h"
#include "common/error.h"
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

void check_header(const FileHeader& h, const char (&magic)[8], const std::string& path) {
    if (std::memcmp(h.magic, magic, 8) != 0)
        throw IoError(path + ": not a gigascroll pack file (wrong magic)");
    if (h.version != kPackVersion)
        throw IoError(path + ": unsupported pack version " + std::to_string(h.version) +
                      " (this build reads version " + std::to_string(kPackVersion) + ")");
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

TilePack::TilePack(const std::string& directory) : directory_(directory) {
    const Manifest m = read_manifest(directory + "/" + kManifestName, &manifest_json_);
    tile_size_ = m.tile_size;
    border_ = m.border;
    codec_ = m.codec;
    table_width_ = m.table_width;
    table_height_ = m.table_height;
    paintings_ = m.paintings;
    entry_count_ = m.tile_count;
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
    check_header(h, kIndexMagic, index_path);
    if (h.entry_size != sizeof(TileEntry) || h.count != entry_count_ ||
        h.data_bytes != entry_count_ * sizeof(TileEntry) ||
        index_size != sizeof(FileHeader) + h.data_bytes) {
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

    // Tile data: keep one descriptor for pread.
    const std::string tiles_path = directory + "/" + kTilesName;
    auto fail = [&](const std::string& message) {
        release();  // the destructor does not run when the constructor throws
        throw IoError(message);
    };
    try {
        require_regular_file(tiles_path);
    } catch (const IoError& e) {
        fail(e.what());
    }
    tiles_fd_ = ::open(tiles_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (tiles_fd_ < 0) fail(tiles_path + ": cannot open: " + std::strerror(errno));
    ::fstat(tiles_fd_, &st);
    tiles_size_ = static_cast<std::uint64_t>(st.st_size);
    FileHeader th{};
    if (tiles_size_ < sizeof(FileHeader) || !pread_all(tiles_fd_, &th, sizeof th, 0))
        fail(tiles_path + ": truncated tile data");
    try {
        check_header(th, kTilesMagic, tiles_path);
    } catch (const IoError& e) {
        fail(e.what());
    }
    if (tiles_size_ != sizeof(FileHeader) + th.data_bytes || th.count != entry_count_)
        fail(tiles_path + ": truncated tile data (" + std::to_string(tiles_size_) +
             " bytes, header promises " + std::to_string(sizeof(FileHeader) + th.data_bytes) + ")");
}

TilePack::~TilePack() { release(); }

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
    if (tiles_fd_ >= 0) ::close(tiles_fd_);
    tiles_fd_ = -1;
}

const TileEntry& TilePack::entry(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                                 std::uint32_t ty) const {
    if (!has_tile(p, l, tx, ty))
        throw InvalidArgument("tile " + key_text(p, l, tx, ty) +
                              " is not stored (padding outside the painting)");
    const PaintingGeometry& g = paintings_[p].geometry;
    return entries_[g.first_entry() + g.tile_index(l, tx, ty)];
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
    if (tx >= g.tiles_x(l) || ty >= g.tiles_y(l)) return false;
    const TileEntry& e = entries_[g.first_entry() + g.tile_index(l, tx, ty)];
    return (e.flags & kTileStored) != 0;
}

TileLocation TilePack::locate(std::uint32_t p, std::uint32_t l, std::uint32_t tx,
                              std::uint32_t ty) const {
    const TileEntry& e = entry(p, l, tx, ty);
    return {e.offset, e.length, e.checksum};
}

void TilePack::read_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty,
                         std::uint8_t* out) const {
    const TileEntry e = entry(p, l, tx, ty);
    const std::size_t bytes = tile_bytes();
    if (e.offset < sizeof(FileHeader) || e.offset + e.length > tiles_size_)
        throw IoError(directory_ + ": index entry of tile " + key_text(p, l, tx, ty) +
                      " points outside tiles.bin");
    if (codec_ == Codec::Raw) {
        if (e.length != bytes)
            throw IoError(directory_ + ": tile " + key_text(p, l, tx, ty) + " has length " +
                          std::to_string(e.length) + ", expected " + std::to_string(bytes));
        if (!pread_all(tiles_fd_, out, bytes, e.offset))
            throw IoError(directory_ + ": short read of tile " + key_text(p, l, tx, ty));
        if (checksum64(out, bytes) != e.checksum)
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
    if (e.offset < sizeof(FileHeader) || e.offset + e.length > tiles_size_)
        throw IoError(directory_ + ": index entry of tile " + key_text(p, l, tx, ty) +
                      " points outside tiles.bin");
    if (codec_ == Codec::Bc1 && e.length != bc1_tile_bytes(tile_size_))
        throw IoError(directory_ + ": bc1 tile " + key_text(p, l, tx, ty) + " has length " +
                      std::to_string(e.length) + ", expected " +
                      std::to_string(bc1_tile_bytes(tile_size_)));
    if (!pread_all(tiles_fd_, into, e.length, e.offset))
        throw IoError(directory_ + ": short read of tile " + key_text(p, l, tx, ty));
    if (checksum64(into, e.length) != e.checksum)
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
