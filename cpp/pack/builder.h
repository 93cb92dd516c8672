// Write side of a tile pack (format in format.h). The image is fed band by band, top to
// bottom. Work per band, on `threads` threads:
//   1. reduce: the MipReducer (mip_reducer.h) cascades the band through every level;
//   2. emit: every tile row whose texels are all present is cut (with clamped borders),
//      checksummed and compressed in parallel, then appended to tiles.bin in order, and the
//      rows no later tile row needs are dropped, so memory grows with the image width, not
//      its area.
// The builder writes tiles.bin, index.bin and, in finish(), manifest.json last. The caller
// builds into a temporary directory and renames it, so an interrupted build never looks done.
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
};

class PackBuilder {
public:
    // Creates directory/tiles.bin (the directory must exist). IoError if it cannot.
    PackBuilder(const std::string& directory, const PackOptions& options);
    ~PackBuilder();
    PackBuilder(const PackBuilder&) = delete;
    PackBuilder& operator=(const PackBuilder&) = delete;

    void begin_painting(const PaintingSpec& spec);
    // rows x width x 3 bytes, row-major, the next rows of the current painting
    // (InvalidArgument if width differs from the painting's or rows overflow its height).
    void add_rows(const std::uint8_t* rgb, std::uint32_t rows, std::uint32_t width);
    void end_painting();
    // Checks the layout (aligned, inside the table, no overlap), writes index.bin and then
    // manifest.json. `page_table_json` is a JSON object merged into the manifest's
    // "page_table" entry (packer name, fill ratios, ...).
    void finish(std::uint32_t table_width, std::uint32_t table_height,
                const std::string& page_table_json = "{}");

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

    std::string directory_;
    PackOptions options_;
    int fd_ = -1;
    std::uint64_t data_bytes_ = 0;
    std::uint64_t tiles_written_ = 0;
    std::vector<Painting> paintings_;
    std::unique_ptr<MipReducer> mip_;  // mip chain of the painting being built
    std::vector<TileRows> rows_;
    bool open_painting_ = false;
    bool finished_ = false;
    std::vector<std::uint8_t> staging_;  // a group of cut tiles before writing (raw codec)
};

}  // namespace gigascroll
