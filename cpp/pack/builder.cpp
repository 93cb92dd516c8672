#include "pack/builder.h"

#include <fcntl.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

#include "common/bits.h"
#include "common/checksum.h"
#include "common/error.h"
#include "common/parallel.h"
#include "pack/bc1.h"
#include "pack/manifest.h"

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

}  // namespace

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

PackBuilder::PackBuilder(const std::string& directory, const PackOptions& options)
    : directory_(directory), options_(options) {
    check_tile_parameters(options.tile_size, options.border);
    require(options.zstd_level >= 1 && options.zstd_level <= 19, "zstd level must be in [1, 19]");
    // Blocks must tile the tile, and tiles start P texels apart: with P a multiple of 4 the
    // overlapping borders of neighbouring tiles are the same blocks of the same texels, so
    // they decode to the same bytes and bilinear filtering stays seamless across tiles.
    require(options.codec != Codec::Bc1 ||
                (options.tile_size % 4 == 0 && (options.tile_size - 2 * options.border) % 4 == 0),
            "bc1 needs tile_size and payload (tile_size - 2 border) to be multiples of 4, got " +
                std::to_string(options.tile_size) + " and " +
                std::to_string(options.tile_size - 2 * options.border));
    const std::string path = directory + "/" + kTilesName;
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) throw IoError(path + ": cannot create: " + std::strerror(errno));
    FileHeader h{};
    std::memcpy(h.magic, kTilesMagic, 8);
    h.version = kPackVersion;
    write_all(&h, sizeof h);  // placeholder; rewritten with the totals in finish()
}

PackBuilder::~PackBuilder() {
    if (fd_ >= 0) ::close(fd_);
}

std::uint32_t PackBuilder::rows_done() const {
    return mip_ ? mip_->level(0).rows_done : 0;
}

void PackBuilder::write_all(const void* data, std::size_t size) {
    write_fully(fd_, data, size, directory_ + "/" + kTilesName);
}

void PackBuilder::begin_painting(const PaintingSpec& spec) {
    require(!finished_, "pack already finished");
    require(!open_painting_, "begin_painting: previous painting not ended");
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
                    sums[i] = checksum64(out, tile_bytes);
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
                    sums[i] = checksum64(out.data(), out.size());
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
                sums[i] = checksum64(out.data(), z);
            }
            ZSTD_freeCCtx(ctx);
        }, options_.threads);

        std::uint64_t offset = sizeof(FileHeader) + data_bytes_;
        for (std::uint32_t i = 0; i < m; ++i) {
            const auto length = static_cast<std::uint32_t>(raw ? tile_bytes : packed[i].size());
            entries[g0 + i] = TileEntry{offset, length, kTileStored, sums[i]};
            offset += length;
            if (!raw) write_all(packed[i].data(), length);
        }
        if (raw) write_all(staging_.data(), std::size_t(m) * tile_bytes);
        data_bytes_ = offset - sizeof(FileHeader);
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
    open_painting_ = false;
}

void PackBuilder::finish(std::uint32_t table_width, std::uint32_t table_height,
                         const std::string& page_table_json) {
    require(!finished_, "pack already finished");
    require(!open_painting_, "finish: a painting is still open");
    require(!paintings_.empty(), "finish: the pack has no painting");
    require(is_pow2(table_width) && is_pow2(table_height),
            "merged page table must be a power of two in each dimension");
    for (std::size_t i = 0; i < paintings_.size(); ++i) {
        const auto& a = paintings_[i];
        const auto& ga = a.geometry;
        require(a.spec.table_x % ga.page_table_width() == 0 && a.spec.table_y % ga.page_table_height() == 0,
                "page table of painting '" + a.spec.name + "' is not aligned to its size");
        require(std::uint64_t(a.spec.table_x) + ga.page_table_width() <= table_width &&
                    std::uint64_t(a.spec.table_y) + ga.page_table_height() <= table_height,
                "page table of painting '" + a.spec.name + "' lies outside the merged table");
        for (std::size_t j = 0; j < i; ++j) {
            const auto& b = paintings_[j];
            const bool apart = a.spec.table_x + ga.page_table_width() <= b.spec.table_x ||
                               b.spec.table_x + b.geometry.page_table_width() <= a.spec.table_x ||
                               a.spec.table_y + ga.page_table_height() <= b.spec.table_y ||
                               b.spec.table_y + b.geometry.page_table_height() <= a.spec.table_y;
            require(apart, "page tables of '" + a.spec.name + "' and '" + b.spec.name + "' overlap");
        }
    }
    // Fails now (on a malformed page_table_json) rather than after the files are written.
    {
        Manifest probe;
        probe.page_table_extra = page_table_json;
        (void)manifest_text(probe);
    }

    // tiles.bin header with the totals, then flush to disk.
    FileHeader th{};
    std::memcpy(th.magic, kTilesMagic, 8);
    th.version = kPackVersion;
    th.count = tiles_written_;
    th.data_bytes = data_bytes_;
    if (::pwrite(fd_, &th, sizeof th, 0) != static_cast<ssize_t>(sizeof th) || ::fsync(fd_) != 0)
        throw IoError(directory_ + "/" + kTilesName + ": write failed: " + std::strerror(errno));
    ::close(fd_);
    fd_ = -1;

    // index.bin
    std::uint64_t count = 0;
    for (const auto& p : paintings_) count += p.entries.size();
    {
        const std::string path = directory_ + "/" + kIndexName;
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) throw IoError(path + ": cannot create: " + std::strerror(errno));
        struct Closer {
            int fd;
            ~Closer() { ::close(fd); }
        } closer{fd};
        FileHeader ih{};
        std::memcpy(ih.magic, kIndexMagic, 8);
        ih.version = kPackVersion;
        ih.entry_size = sizeof(TileEntry);
        ih.count = count;
        ih.data_bytes = count * sizeof(TileEntry);
        write_fully(fd, &ih, sizeof ih, path);
        for (const auto& p : paintings_)
            write_fully(fd, p.entries.data(), p.entries.size() * sizeof(TileEntry), path);
        if (::fsync(fd) != 0) throw IoError(path + ": fsync failed: " + std::strerror(errno));
    }

    // manifest.json, last.
    Manifest m;
    m.tile_size = options_.tile_size;
    m.border = options_.border;
    m.codec = options_.codec;
    m.tile_count = count;
    m.tiles_bytes = sizeof(FileHeader) + data_bytes_;
    m.table_width = table_width;
    m.table_height = table_height;
    m.page_table_extra = page_table_json;
    for (const auto& p : paintings_) {
        PaintingInfo info{p.spec.name, p.spec.source, p.spec.conversion, p.geometry, p.spec.colour};
        info.geometry.place(p.spec.table_x, p.spec.table_y, p.first_entry);
        m.paintings.push_back(std::move(info));
    }
    write_manifest(directory_ + "/" + kManifestName, m);
    finished_ = true;
}

}  // namespace gigascroll
