// Write side of a tile pack (format in format.h). The image is fed band by band, top to
// bottom. Work per band, on `threads` threads:
//   1. reduce: the MipReducer (mip_reducer.h) cascades the band through every level;
//   2. emit: every tile row whose texels are all present is cut (with clamped borders),
//      checksummed and compressed in parallel, then appended to tiles.bin in order, and the
//      rows no later tile row needs are dropped, so memory grows with the image width, not
//      its area.
// The builder writes one tile file per painting (tiles-NNNNN.bin, closed and fsync'ed at
// end_painting), then in finish() index.bin and manifest.json last. The caller builds into a
// temporary directory and renames it, so an interrupted build never looks done.
// Shards: a builder whose first_painting is i builds paintings i, i+1, ... of a larger pack
// and finish_shard() writes their index entries to shard-NNNNN.idx; the tile file and entries
// are exactly the bytes a whole-pack build writes for those paintings (offsets count from the
// start of the painting's own file, checksums are seeded with the global tile key), so
// assemble_pack() merges shards by writing index.bin and the manifest, copying no tile data.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pack/bc1.h"
#include "pack/format.h"
#include "pack/geometry.h"
#include "pack/mip_reducer.h"

namespace gigascroll {

struct PackOptions {
    std::uint32_t tile_size = 128;
    std::uint32_t border = 4;
    Codec codec = Codec::Raw;
    int zstd_level = 3;
    Bc1Fit bc1_fit = Bc1Fit::Range;
    unsigned threads = 0;  // 0 = all cores
};

struct PaintingSpec {
    std::string name;
    std::string source;
    std::string conversion;
    std::uint32_t width = 0, height = 0;
    std::uint32_t table_x = 0, table_y = 0;  // offset in the merged page table
    std::string colour;  // a JSON object (colour management at ingest) or empty for none
    // >= 0: an instance of that painting (manifest.h's PaintingInfo::instance_of): no rows,
    // no tile file, no index entries; width and height are taken from the source.
    std::int64_t instance_of = -1;
};

// The index file of a shard's painting: "shard-00042.idx" (FileHeader + its TileEntries).
std::string shard_index_name(std::uint32_t painting);

class PackBuilder {
public:
    // Builds into `directory` (it must exist), the first painting being painting
    // `first_painting` of the pack (InvalidArgument past kMaxPackPaintings).
    PackBuilder(const std::string& directory, const PackOptions& options,
                std::uint32_t first_painting = 0);
    ~PackBuilder();
    PackBuilder(const PackBuilder&) = delete;
    PackBuilder& operator=(const PackBuilder&) = delete;

    void begin_painting(const PaintingSpec& spec);
    // rows x width x 3 bytes, row-major, the next rows of the current painting
    // (InvalidArgument if width differs from the painting's or rows overflow its height).
    void add_rows(const std::uint8_t* rgb, std::uint32_t rows, std::uint32_t width);
    void end_painting();
    // Adds a painting that is an instance of stored painting spec.instance_of (one built by
    // this builder). Instances come after every stored painting: InvalidArgument for a
    // stored painting begun after one, for a painting still open or a bad source.
    void add_instance(const PaintingSpec& spec);
    // Checks the layout (aligned, inside the table, no overlap), writes index.bin and then
    // manifest.json. `page_table_json` is a JSON object merged into the manifest's
    // "page_table" entry (packer name, fill ratios, ...).
    // Only for a builder whose first_painting is 0.
    void finish(std::uint32_t table_width, std::uint32_t table_height,
                const std::string& page_table_json = "{}");
    // Writes shard-NNNNN.idx of every painting built (fsync'ed); the builder is then done.
    void finish_shard();
    // Merges shards in `directory` (one per stored spec, painting i's shard-i.idx and tile
    // file; specs with instance_of >= 0, after the stored ones, are instances):
    // checks each shard's index against the painting's geometry, writes index.bin and
    // manifest.json (validated first). IoError for a missing or inconsistent shard.
    static void assemble(const std::string& directory, const PackOptions& options,
                         const std::vector<PaintingSpec>& paintings, std::uint32_t table_width,
                         std::uint32_t table_height, const std::string& page_table_json = "{}");

    const PackOptions& options() const { return options_; }
    std::uint32_t rows_done() const;  // level-0 rows of the current painting
    std::uint64_t tiles_written() const { return tiles_written_; }
    std::uint64_t bytes_written() const { return data_bytes_; }

private:
    struct TileRows;  // per level: the next tile row to cut, the entries cut so far
    struct Painting;

    void emit_ready_tiles();
    void emit_tile_row(const MipReducer::Level& lv, TileRows& rows, std::uint32_t ty);
    void write_all(const void* data, std::size_t size);
    std::string tiles_path() const;

    std::string directory_;
    PackOptions options_;
    std::uint32_t first_painting_ = 0;
    int fd_ = -1;                     // tile file of the painting being built
    std::uint64_t file_bytes_ = 0;    // its data bytes so far
    std::uint64_t data_bytes_ = 0;    // all tile files' data bytes
    std::uint64_t tiles_written_ = 0;
    std::vector<Painting> paintings_;
    std::vector<PaintingSpec> instances_;  // after paintings_, in the order added
    std::unique_ptr<MipReducer> mip_;  // mip chain of the painting being built
    std::vector<TileRows> rows_;
    bool open_painting_ = false;
    bool finished_ = false;
    std::vector<std::uint8_t> staging_;  // a group of cut tiles before writing (raw codec)
};

}  // namespace gigascroll
