#include "pack/builder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "common/bits.h"
#include "common/checksum.h"
#include "common/error.h"
#include "common/parallel.h"
#include "pack/bc1.h"
#include "pack/manifest.h"
#include "pack/tile_key.h"

namespace gigascroll {
namespace {

// write() until done; IoError with the reason (ENOSPC: disk full, EFBIG, ...) otherwise.
void write_fully(int fd, const void* data, std::size_t size, const std::string& path) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw IoError(path + ": write failed: " + std::strerror(n < 0 ? errno : EIO));
        p += n;
        size -= static_cast<std::size_t>(n);
    }
}

void write_header(int fd, const char (&magic)[8], std::uint32_t entry_size, std::uint64_t count,
                  std::uint64_t data_bytes, const std::string& path) {
    FileHeader h{};
    std::memcpy(h.magic, magic, 8);
    h.version = kPackVersion;
    h.entry_size = entry_size;
    h.count = count;
    h.data_bytes = data_bytes;
    if (::pwrite(fd, &h, sizeof h, 0) != static_cast<ssize_t>(sizeof h))
        throw IoError(path + ": write failed: " + std::strerror(errno));
}

struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
};

// Writes FileHeader + entries to path, fsync'ed.
void write_index(const std::string& path, const std::vector<const std::vector<TileEntry>*>& parts) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw IoError(path + ": cannot create: " + std::strerror(errno));
    FdCloser closer{fd};
    std::uint64_t count = 0;
    for (const auto* p : parts) count += p->size();
    FileHeader ih{};
    std::memcpy(ih.magic, kIndexMagic, 8);
    ih.version = kPackVersion;
    ih.entry_size = sizeof(TileEntry);
    ih.count = count;
    ih.data_bytes = count * sizeof(TileEntry);
    write_fully(fd, &ih, sizeof ih, path);
    for (const auto* p : parts) write_fully(fd, p->data(), p->size() * sizeof(TileEntry), path);
    if (::fsync(fd) != 0) throw IoError(path + ": fsync failed: " + std::strerror(errno));
}

}  // namespace

std::string shard_index_name(std::uint32_t painting) {
    char name[32];
    std::snprintf(name, sizeof name, "shard-%05u.idx", painting);
    return name;
}

struct PackBuilder::TileRows {
    std::uint32_t next_tile_row = 0;
    std::vector<TileEntry> entries;      // tiles_x * tiles_y
};

struct PackBuilder::Painting {
    PaintingSpec spec;
    PaintingGeometry geometry;
    std::uint64_t first_entry = 0;
    std::vector<TileEntry> entries;  // all levels, in index order
};

PackBuilder::PackBuilder(const std::string& directory, const PackOptions& options,
                         std::uint32_t first_painting)
    : directory_(directory), options_(options), first_painting_(first_painting) {
    check_tile_parameters(options.tile_size, options.border);
    require(options.zstd_level >= 1 && options.zstd_level <= 19, "zstd level must be in [1, 19]");
    require(first_painting < kMaxPackPaintings,
            "first_painting " + std::to_string(first_painting) + " is past the " +
                std::to_string(kMaxPackPaintings) + " paintings a pack can hold");
    struct stat st {};
    if (::stat(directory.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        throw IoError(directory + ": not a directory to build a pack in");
    // Blocks must tile the tile, and tiles start P texels apart: with P a multiple of 4 the
    // overlapping borders of neighbouring tiles are the same blocks of the same texels, so
    // they decode to the same bytes and bilinear filtering stays seamless across tiles.
    require(options.codec != Codec::Bc1 ||
                (options.tile_size % 4 == 0 && (options.tile_size - 2 * options.border) % 4 == 0),
            "bc1 needs tile_size and payload (tile_size - 2 border) to be multiples of 4, got " +
                std::to_string(options.tile_size) + " and " +
                std::to_string(options.tile_size - 2 * options.border));
}

PackBuilder::~PackBuilder() {
    if (fd_ >= 0) ::close(fd_);
}

std::string PackBuilder::tiles_path() const {
    return directory_ + "/" +
           tile_file_name(first_painting_ + static_cast<std::uint32_t>(paintings_.size()) - 1);
}

std::uint32_t PackBuilder::rows_done() const {
    return mip_ ? mip_->level(0).rows_done : 0;
}

void PackBuilder::write_all(const void* data, std::size_t size) {
    write_fully(fd_, data, size, tiles_path());
}

void PackBuilder::begin_painting(const PaintingSpec& spec) {
    require(!finished_, "pack already finished");
    require(!open_painting_, "begin_painting: previous painting not ended");
    require(instances_.empty(), "begin_painting: instances come after every stored painting");
    require(spec.instance_of < 0, "begin_painting: an instance is added with add_instance");
    require(std::uint64_t(first_painting_) + paintings_.size() < kMaxPackPaintings,
            "a pack holds at most " + std::to_string(kMaxPackPaintings) +
                " paintings (the tile key's 16-bit painting field)");
    Painting p;
    p.spec = spec;
    p.geometry = PaintingGeometry(spec.width, spec.height, options_.tile_size, options_.border);
    p.first_entry = paintings_.empty()
                        ? 0
                        : paintings_.back().first_entry + paintings_.back().geometry.total_tiles();
    mip_ = std::make_unique<MipReducer>(p.geometry, options_.threads);
    rows_.assign(p.geometry.levels(), TileRows{});
    for (std::uint32_t l = 0; l < p.geometry.levels(); ++l)
        rows_[l].entries.assign(p.geometry.tile_count(l), TileEntry{});
    paintings_.push_back(std::move(p));
    const std::string path = tiles_path();
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw IoError(path + ": cannot create: " + std::strerror(errno));
    const FileHeader placeholder{};  // rewritten with the totals in end_painting()
    write_all(&placeholder, sizeof placeholder);
    file_bytes_ = 0;
    open_painting_ = true;
}

void PackBuilder::add_rows(const std::uint8_t* rgb, std::uint32_t rows, std::uint32_t width) {
    require(open_painting_, "add_rows: no painting begun");
    const PaintingGeometry& g = paintings_.back().geometry;
    require(width == g.width(), "add_rows: rows are " + std::to_string(width) +
                                  " pixels wide, the painting is " + std::to_string(g.width()));
    require(std::uint64_t(rows_done()) + rows <= g.height(),
            "add_rows: " + std::to_string(rows) + " rows at row " +
                std::to_string(rows_done()) + " overflow the image height " +
                std::to_string(g.height()));
    // Sub-bands of at most one payload height: the level-0 window then never holds more
    // than about two tile rows, whatever band size the caller uses.
    const std::uint32_t step = g.payload();
    for (std::uint32_t done = 0; done < rows; done += step) {
        const std::uint32_t n = std::min(step, rows - done);
        mip_->add_rows(rgb + std::size_t(done) * width * 3, n);
        emit_ready_tiles();
    }
}

void PackBuilder::emit_ready_tiles() {
    const std::uint32_t P = options_.tile_size - 2 * options_.border;
    const std::uint32_t b = options_.border;
    for (std::size_t l = 0; l < rows_.size(); ++l) {
        const MipReducer::Level& lv = mip_->level(l);
        TileRows& tr = rows_[l];
        while (tr.next_tile_row < lv.geo.tiles_y) {
            const std::uint32_t ty = tr.next_tile_row;
            const std::uint32_t last =
                std::min<std::uint64_t>(lv.geo.height - 1, std::uint64_t(ty) * P + P + b - 1);
            if (last >= lv.rows_done) break;
            emit_tile_row(lv, tr, ty);
            ++tr.next_tile_row;
        }
        // Drop the rows no later tile row needs.
        const std::uint32_t keep_from =
            tr.next_tile_row < lv.geo.tiles_y
                ? std::min(lv.rows_done,
                           static_cast<std::uint32_t>(std::max<std::int64_t>(
                               0, std::int64_t(tr.next_tile_row) * P - b)))
                : lv.rows_done;
        mip_->drop_rows(l, keep_from);
    }
}

void PackBuilder::emit_tile_row(const MipReducer::Level& lv, TileRows& tr, std::uint32_t ty) {
    const std::uint32_t T = options_.tile_size, b = options_.border, P = T - 2 * b;
    const std::uint32_t W = lv.geo.width, H = lv.geo.height;
    const std::size_t tile_bytes = std::size_t(T) * T * 3;
    const bool raw = options_.codec == Codec::Raw;

    auto cut = [&](std::uint32_t tx, std::uint8_t* out) {
        const std::int64_t x0 = std::int64_t(tx) * P - b, y0 = std::int64_t(ty) * P - b;
        const bool inside_x = x0 >= 0 && x0 + T <= W;
        for (std::uint32_t j = 0; j < T; ++j) {
            const std::int64_t y = std::clamp<std::int64_t>(y0 + j, 0, H - 1);
            const std::uint8_t* row = lv.window.data() + std::size_t(y - lv.win_base) * W * 3;
            std::uint8_t* o = out + std::size_t(j) * T * 3;
            if (inside_x) {
                std::memcpy(o, row + x0 * 3, std::size_t(T) * 3);
            } else {
                for (std::uint32_t i = 0; i < T; ++i) {
                    const std::int64_t x = std::clamp<std::int64_t>(x0 + i, 0, W - 1);
                    std::memcpy(o + 3 * i, row + 3 * x, 3);
                }
            }
        }
    };

    // Groups of tiles bound the staging memory; within a group tiles are cut, checksummed
    // and compressed in parallel, then appended to tiles.bin in tx order.
    constexpr std::uint32_t kGroup = 64;
    const std::uint32_t n = lv.geo.tiles_x;
    const auto level = static_cast<std::uint32_t>(&tr - rows_.data());
    const std::uint32_t painting = first_painting_ + static_cast<std::uint32_t>(paintings_.size()) - 1;
    const auto key = [&](std::uint32_t tx) { return TileKey{painting, level, tx, ty}.packed(); };
    TileEntry* entries = tr.entries.data() + std::size_t(ty) * n;
    std::vector<std::vector<std::uint8_t>> packed(raw ? 0 : kGroup);
    std::uint64_t sums[kGroup];
    for (std::uint32_t g0 = 0; g0 < n; g0 += kGroup) {
        const std::uint32_t m = std::min(kGroup, n - g0);
        if (raw) staging_.resize(m * tile_bytes);
        parallel_for(m, 4, [&](std::size_t begin, std::size_t end) {
            if (raw) {
                for (std::size_t i = begin; i < end; ++i) {
                    std::uint8_t* out = staging_.data() + i * tile_bytes;
                    cut(static_cast<std::uint32_t>(g0 + i), out);
                    sums[i] = tile_checksum(kPackVersion, key(g0 + i), out, tile_bytes);
                }
                return;
            }
            std::vector<std::uint8_t> tile(tile_bytes);
            if (options_.codec == Codec::Bc1) {
                for (std::size_t i = begin; i < end; ++i) {
                    cut(static_cast<std::uint32_t>(g0 + i), tile.data());
                    auto& out = packed[i];
                    out.resize(bc1_tile_bytes(T));
                    bc1_encode_tile(tile.data(), T, out.data(), options_.bc1_fit);
                    sums[i] = tile_checksum(kPackVersion, key(g0 + i), out.data(), out.size());
                }
                return;
            }
            ZSTD_CCtx* ctx = ZSTD_createCCtx();
            for (std::size_t i = begin; i < end; ++i) {
                cut(static_cast<std::uint32_t>(g0 + i), tile.data());
                auto& out = packed[i];
                out.resize(ZSTD_compressBound(tile_bytes));
                const std::size_t z = ZSTD_compressCCtx(ctx, out.data(), out.size(), tile.data(),
                                                        tile_bytes, options_.zstd_level);
                if (ZSTD_isError(z)) {
                    ZSTD_freeCCtx(ctx);
                    throw IoError(std::string("zstd compression failed: ") + ZSTD_getErrorName(z));
                }
                out.resize(z);
                sums[i] = tile_checksum(kPackVersion, key(g0 + i), out.data(), z);
            }
            ZSTD_freeCCtx(ctx);
        }, options_.threads);

        std::uint64_t offset = sizeof(FileHeader) + file_bytes_;
        const auto file = static_cast<std::uint16_t>(painting);
        for (std::uint32_t i = 0; i < m; ++i) {
            const auto length = static_cast<std::uint32_t>(raw ? tile_bytes : packed[i].size());
            entries[g0 + i] = TileEntry{offset, length, kTileStored, file, sums[i]};
            offset += length;
            if (!raw) write_all(packed[i].data(), length);
        }
        if (raw) write_all(staging_.data(), std::size_t(m) * tile_bytes);
        data_bytes_ += offset - sizeof(FileHeader) - file_bytes_;
        file_bytes_ = offset - sizeof(FileHeader);
        tiles_written_ += m;
    }
}

void PackBuilder::end_painting() {
    require(open_painting_, "end_painting: no painting begun");
    Painting& p = paintings_.back();
    require(rows_done() == p.geometry.height(),
            "end_painting: only " + std::to_string(rows_done()) + " of " +
                std::to_string(p.geometry.height()) + " rows were added");
    for (std::size_t l = 0; l < rows_.size(); ++l) {
        const MipReducer::Level& lv = mip_->level(l);
        GS_CHECK(rows_[l].next_tile_row == lv.geo.tiles_y && lv.rows_done == lv.geo.height);
        p.entries.insert(p.entries.end(), rows_[l].entries.begin(), rows_[l].entries.end());
    }
    mip_.reset();
    rows_.clear();
    const std::string path = tiles_path();
    write_header(fd_, kTilesMagic, 0, p.entries.size(), file_bytes_, path);
    if (::fsync(fd_) != 0) throw IoError(path + ": fsync failed: " + std::strerror(errno));
    ::close(fd_);
    fd_ = -1;
    open_painting_ = false;
}

void PackBuilder::add_instance(const PaintingSpec& spec) {
    require(!finished_, "pack already finished");
    require(!open_painting_, "add_instance: a painting is still open");
    require(first_painting_ == 0, "add_instance: a shard builder has no instances (assemble "
                                  "adds them)");
    require(spec.instance_of >= 0 && std::uint64_t(spec.instance_of) < paintings_.size(),
            "add_instance: painting '" + spec.name + "' names source " +
                std::to_string(spec.instance_of) + ", the builder has " +
                std::to_string(paintings_.size()) + " stored paintings");
    require(paintings_.size() + instances_.size() < kMaxPackPaintings,
            "a pack holds at most " + std::to_string(kMaxPackPaintings) +
                " paintings (the tile key's 16-bit painting field)");
    PaintingSpec s = spec;
    const PaintingGeometry& src = paintings_[std::size_t(spec.instance_of)].geometry;
    s.width = src.width(), s.height = src.height();
    instances_.push_back(std::move(s));
}

namespace {

// The manifest entry of an instance: its source's geometry, placed at its own table offset
// and at the source's first entry.
// Source, conversion and colour record describe the stored pixels: the source's.
PaintingInfo instance_info(const PaintingSpec& s, const std::vector<PaintingInfo>& paintings,
                           std::size_t stored) {
    require(s.instance_of >= 0 && std::uint64_t(s.instance_of) < stored,
            "instance '" + s.name + "': source " + std::to_string(s.instance_of) +
                " is not a stored painting");
    const PaintingInfo& src = paintings[std::size_t(s.instance_of)];
    PaintingInfo info{s.name, src.source, src.conversion, src.geometry, src.colour};
    info.geometry.place(s.table_x, s.table_y, src.geometry.first_entry());
    info.instance_of = s.instance_of;
    return info;
}

}  // namespace

void PackBuilder::finish(std::uint32_t table_width, std::uint32_t table_height,
                         const std::string& page_table_json) {
    require(!finished_, "pack already finished");
    require(!open_painting_, "finish: a painting is still open");
    require(!paintings_.empty(), "finish: the pack has no painting");
    require(first_painting_ == 0, "finish: a shard builder ends with finish_shard()");
    Manifest m;
    m.tile_size = options_.tile_size;
    m.border = options_.border;
    m.codec = options_.codec;
    m.tiles_bytes = 0;
    m.table_width = table_width;
    m.table_height = table_height;
    m.page_table_extra = page_table_json;
    std::vector<const std::vector<TileEntry>*> parts;
    for (std::size_t i = 0; i < paintings_.size(); ++i) {
        const Painting& p = paintings_[i];
        PaintingInfo info{p.spec.name, p.spec.source, p.spec.conversion, p.geometry, p.spec.colour};
        info.geometry.place(p.spec.table_x, p.spec.table_y, p.first_entry);
        m.paintings.push_back(std::move(info));
        m.tile_files.push_back(tile_file_name(static_cast<std::uint32_t>(i)));
        m.tile_count += p.entries.size();
        parts.push_back(&p.entries);
    }
    const std::size_t stored = m.paintings.size();
    for (const PaintingSpec& s : instances_)
        m.paintings.push_back(instance_info(s, m.paintings, stored));
    m.tiles_bytes = paintings_.size() * sizeof(FileHeader) + data_bytes_;
    // Fails now (bad layout, malformed page_table_json) rather than after index.bin is written.
    (void)manifest_text(m);
    write_index(directory_ + "/" + kIndexName, parts);
    write_manifest(directory_ + "/" + kManifestName, m);  // last
    finished_ = true;
}

void PackBuilder::finish_shard() {
    require(!finished_, "pack already finished");
    require(!open_painting_, "finish_shard: a painting is still open");
    require(!paintings_.empty(), "finish_shard: the shard has no painting");
    for (std::size_t i = 0; i < paintings_.size(); ++i)
        write_index(directory_ + "/" + shard_index_name(first_painting_ + static_cast<std::uint32_t>(i)),
                    {&paintings_[i].entries});
    finished_ = true;
}

void PackBuilder::assemble(const std::string& directory, const PackOptions& options,
                           const std::vector<PaintingSpec>& specs, std::uint32_t table_width,
                           std::uint32_t table_height, const std::string& page_table_json) {
    check_tile_parameters(options.tile_size, options.border);
    require(!specs.empty(), "assemble: no paintings");
    require(specs.size() <= kMaxPackPaintings,
            "a pack holds at most " + std::to_string(kMaxPackPaintings) + " paintings");
    Manifest m;
    m.tile_size = options.tile_size;
    m.border = options.border;
    m.codec = options.codec;
    m.table_width = table_width;
    m.table_height = table_height;
    m.page_table_extra = page_table_json;
    std::size_t stored = 0;
    while (stored < specs.size() && specs[stored].instance_of < 0) ++stored;
    for (std::size_t i = stored; i < specs.size(); ++i)
        require(specs[i].instance_of >= 0, "assemble: painting '" + specs[i].name +
                                                "' is stored after an instance (instances come last)");
    std::vector<std::vector<TileEntry>> entries(stored);
    for (std::size_t i = 0; i < stored; ++i) {
        const PaintingSpec& s = specs[i];
        const auto pi = static_cast<std::uint32_t>(i);
        PaintingInfo info{s.name, s.source, s.conversion,
                          PaintingGeometry(s.width, s.height, options.tile_size, options.border),
                          s.colour};
        info.geometry.place(s.table_x, s.table_y, m.tile_count);
        const std::uint64_t n = info.geometry.total_tiles();
        // The shard's index: exactly n entries, all in this painting's own tile file.
        const std::string path = directory + "/" + shard_index_name(pi);
        require_regular_file(path);
        const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) throw IoError(path + ": cannot open: " + std::strerror(errno));
        FdCloser closer{fd};
        struct stat st {};
        ::fstat(fd, &st);
        FileHeader h{};
        if (::pread(fd, &h, sizeof h, 0) != static_cast<ssize_t>(sizeof h) ||
            std::memcmp(h.magic, kIndexMagic, 8) != 0 || h.version != kPackVersion ||
            h.entry_size != sizeof(TileEntry) || h.count != n ||
            std::uint64_t(st.st_size) != sizeof(FileHeader) + n * sizeof(TileEntry))
            throw IoError(path + ": not the index of a finished shard of painting '" + s.name + "'");
        entries[i].resize(n);
        const std::size_t bytes = n * sizeof(TileEntry);
        if (::pread(fd, entries[i].data(), bytes, sizeof h) != static_cast<ssize_t>(bytes))
            throw IoError(path + ": short read");
        for (const TileEntry& e : entries[i])
            if (e.file != pi || e.flags != kTileStored)
                throw IoError(path + ": an entry does not belong to painting " + std::to_string(pi));
        const std::string tiles = directory + "/" + tile_file_name(pi);
        require_regular_file(tiles);
        if (::stat(tiles.c_str(), &st) != 0) throw IoError(tiles + ": cannot stat");
        m.tiles_bytes += std::uint64_t(st.st_size);
        m.tile_count += n;
        m.tile_files.push_back(tile_file_name(pi));
        m.paintings.push_back(std::move(info));
    }
    for (std::size_t i = stored; i < specs.size(); ++i) {
        m.paintings.push_back(instance_info(specs[i], m.paintings, stored));
    }
    (void)manifest_text(m);  // validate before writing anything
    std::vector<const std::vector<TileEntry>*> parts;
    for (const auto& e : entries) parts.push_back(&e);
    write_index(directory + "/" + kIndexName, parts);
    write_manifest(directory + "/" + kManifestName, m);
}

}  // namespace gigascroll
