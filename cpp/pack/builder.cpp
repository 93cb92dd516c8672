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

struct PackBuilder::Level {
    LevelGeometry geo;
    std::uint32_t shift = 0;             // l: a texel covers 2^l x 2^l level-0 pixels
    std::vector<std::uint8_t> window;    // texel rows [win_base, win_base + win_rows)
    std::uint32_t win_base = 0, win_rows = 0;
    std::uint32_t rows_done = 0;         // rows of this level completed so far
    std::uint32_t next_tile_row = 0;
    std::vector<std::uint64_t> acc;      // level-0 sums of the row in progress (levels >= 1)
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
    return levels_.empty() ? 0 : levels_[0].rows_done;
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
    levels_.clear();
    levels_.resize(p.geometry.levels());
    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        lv.geo = p.geometry.level(std::uint32_t(l));
        lv.shift = static_cast<std::uint32_t>(l);
        if (l > 0) lv.acc.assign(std::size_t(lv.geo.width) * 3, 0);
        lv.entries.assign(std::size_t(lv.geo.tiles_x) * lv.geo.tiles_y, TileEntry{});
    }
    paintings_.push_back(std::move(p));
    open_painting_ = true;
}

void PackBuilder::add_rows(const std::uint8_t* rgb, std::uint32_t rows, std::uint32_t width) {
    require(open_painting_, "add_rows: no painting begun");
    const PaintingGeometry& g = paintings_.back().geometry;
    require(width == g.width(), "add_rows: rows are " + std::to_string(width) +
                                  " pixels wide, the painting is " + std::to_string(g.width()));
    require(std::uint64_t(levels_[0].rows_done) + rows <= g.height(),
            "add_rows: " + std::to_string(rows) + " rows at row " +
                std::to_string(levels_[0].rows_done) + " overflow the image height " +
                std::to_string(g.height()));
    // Sub-bands of at most one payload height: the level-0 window then never holds more
    // than about two tile rows, whatever band size the caller uses.
    const std::uint32_t step = g.payload();
    for (std::uint32_t done = 0; done < rows; done += step) {
        const std::uint32_t n = std::min(step, rows - done);
        add_sub_band(rgb + std::size_t(done) * width * 3, n);
    }
}

void PackBuilder::add_sub_band(const std::uint8_t* rgb, std::uint32_t rows) {
    const PaintingGeometry& g = paintings_.back().geometry;
    const std::uint32_t y0 = levels_[0].rows_done;

    // Rows each level completes in this band; grow the windows before the parallel part.
    std::vector<std::uint32_t> done(levels_.size());
    done[0] = y0 + rows;
    for (std::size_t l = 1; l < levels_.size(); ++l) {
        const Level& up = levels_[l - 1];
        done[l] = done[l - 1] == up.geo.height ? levels_[l].geo.height : done[l - 1] / 2;
    }
    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        const std::uint32_t added = done[l] - lv.rows_done;
        lv.window.resize(std::size_t(lv.win_rows + added) * lv.geo.width * 3);
    }

    // Column strips aligned to 2^(levels-1) stay independent through the whole chain.
    const std::uint32_t align = 1u << (levels_.size() - 1);
    const std::uint32_t strip = std::max<std::uint32_t>(align, ((4096 + align - 1) / align) * align);
    const std::size_t strips = (g.width() + strip - 1) / strip;
    parallel_for(strips, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t x0 = static_cast<std::uint32_t>(s * strip);
            const std::uint32_t x1 = std::min<std::uint32_t>(g.width(), x0 + strip);
            reduce_strip(x0, x1, rgb, y0, rows);
        }
    }, options_.threads);

    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        lv.win_rows += done[l] - lv.rows_done;
        lv.rows_done = done[l];
    }
    emit_ready_tiles();
}

// Level 0 rows [y_begin, y_begin + rows), columns [x0, x1): copy into the window and cascade
// the sums down the chain. Only this strip's columns of any buffer are touched.
void PackBuilder::reduce_strip(std::uint32_t x0, std::uint32_t x1, const std::uint8_t* rgb,
                               std::uint32_t y_begin, std::uint32_t rows) {
    Level& l0 = levels_[0];
    const std::uint32_t W = l0.geo.width;
    for (std::uint32_t i = 0; i < rows; ++i) {
        const std::uint32_t y = y_begin + i;
        const std::uint8_t* src = rgb + (std::size_t(i) * W + x0) * 3;
        std::uint8_t* dst = l0.window.data() + (std::size_t(y - l0.win_base) * W + x0) * 3;
        std::memcpy(dst, src, std::size_t(x1 - x0) * 3);
        if (levels_.size() == 1) continue;
        std::uint64_t* acc = levels_[1].acc.data();
        const std::uint32_t X0 = x0 >> 1, X1 = (x1 + 1) >> 1;
        for (std::uint32_t X = X0; X < X1; ++X) {
            const std::uint32_t xa = 2 * X, xb = std::min(2 * X + 1, W - 1);
            const std::uint8_t* a = src + std::size_t(xa - x0) * 3;
            for (int c = 0; c < 3; ++c) acc[3 * X + c] += a[c];
            if (xb != xa) {
                const std::uint8_t* bp = src + std::size_t(xb - x0) * 3;
                for (int c = 0; c < 3; ++c) acc[3 * X + c] += bp[c];
            }
        }
        if ((y & 1) || y == l0.geo.height - 1) finish_row(1, y >> 1, X0, X1);
    }
}

// Row y of level l is complete in columns [x0, x1) of that level: turn its sums into texels,
// pass them on to level l+1 and recurse when that row completes too.
void PackBuilder::finish_row(std::size_t l, std::uint32_t y, std::uint32_t x0, std::uint32_t x1) {
    Level& lv = levels_[l];
    const PaintingGeometry& g = paintings_.back().geometry;
    const std::uint32_t s = lv.shift;
    const std::uint64_t full = 1ull << (2 * s);
    const std::uint64_t cy =
        std::min<std::uint64_t>(g.height(), (std::uint64_t(y) + 1) << s) - (std::uint64_t(y) << s);
    std::uint64_t* acc = lv.acc.data();
    std::uint8_t* dst = lv.window.data() + std::size_t(y - lv.win_base) * lv.geo.width * 3;
    const bool last_level = l + 1 == levels_.size();
    std::uint64_t* next = last_level ? nullptr : levels_[l + 1].acc.data();
    for (std::uint32_t x = x0; x < x1; ++x) {
        const std::uint64_t cx =
            std::min<std::uint64_t>(g.width(), (std::uint64_t(x) + 1) << s) - (std::uint64_t(x) << s);
        const std::uint64_t count = cx * cy;
        std::uint64_t* a = acc + 3 * std::size_t(x);
        if (count == full) {
            for (int c = 0; c < 3; ++c) dst[3 * x + c] = std::uint8_t((a[c] + full / 2) >> (2 * s));
        } else {
            for (int c = 0; c < 3; ++c) dst[3 * x + c] = std::uint8_t((a[c] + count / 2) / count);
        }
        if (next) {
            std::uint64_t* n = next + 3 * std::size_t(x >> 1);
            for (int c = 0; c < 3; ++c) n[c] += a[c];
        }
        a[0] = a[1] = a[2] = 0;
    }
    if (!last_level && ((y & 1) || y == lv.geo.height - 1))
        finish_row(l + 1, y >> 1, x0 >> 1, (x1 + 1) >> 1);
}

void PackBuilder::emit_ready_tiles() {
    const std::uint32_t P = options_.tile_size - 2 * options_.border;
    const std::uint32_t b = options_.border;
    for (Level& lv : levels_) {
        while (lv.next_tile_row < lv.geo.tiles_y) {
            const std::uint32_t ty = lv.next_tile_row;
            const std::uint32_t last =
                std::min<std::uint64_t>(lv.geo.height - 1, std::uint64_t(ty) * P + P + b - 1);
            if (last >= lv.rows_done) break;
            emit_tile_row(lv, ty);
            ++lv.next_tile_row;
        }
        // Drop the rows no later tile row needs.
        const std::uint32_t keep_from =
            lv.next_tile_row < lv.geo.tiles_y
                ? std::min(lv.rows_done,
                           static_cast<std::uint32_t>(std::max<std::int64_t>(
                               0, std::int64_t(lv.next_tile_row) * P - b)))
                : lv.rows_done;
        if (keep_from > lv.win_base) {
            const std::size_t row_bytes = std::size_t(lv.geo.width) * 3;
            const std::uint32_t drop = keep_from - lv.win_base;
            std::memmove(lv.window.data(), lv.window.data() + drop * row_bytes,
                         (lv.win_rows - drop) * row_bytes);
            lv.win_rows -= drop;
            lv.win_base = keep_from;
            lv.window.resize(lv.win_rows * row_bytes);
        }
    }
}

void PackBuilder::emit_tile_row(Level& lv, std::uint32_t ty) {
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
    TileEntry* entries = lv.entries.data() + std::size_t(ty) * n;
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
    require(levels_[0].rows_done == p.geometry.height(),
            "end_painting: only " + std::to_string(levels_[0].rows_done) + " of " +
                std::to_string(p.geometry.height()) + " rows were added");
    for (Level& lv : levels_) {
        if (lv.next_tile_row != lv.geo.tiles_y || lv.rows_done != lv.geo.height)
            throw std::logic_error("pack builder: level incomplete at end of painting");
        p.entries.insert(p.entries.end(), lv.entries.begin(), lv.entries.end());
    }
    levels_.clear();
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
        PaintingInfo info{p.spec.name, p.spec.source, p.spec.conversion, p.geometry};
        info.geometry.place(p.spec.table_x, p.spec.table_y, p.first_entry);
        m.paintings.push_back(std::move(info));
    }
    write_manifest(directory_ + "/" + kManifestName, m);
    finished_ = true;
}

}  // namespace gigascroll
