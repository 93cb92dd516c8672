// Write side of a tile pack (format in pack_format.h). The image is fed band by band, top to
// bottom; the builder keeps, per mip level, only the rows that the next tile row still needs,
// so memory grows with the image width, not its area.
//
// A mip texel is the rounded average of the real level-0 pixels under it: each level keeps the
// exact 64-bit sums of its texels' level-0 pixels and their counts, never averages of averages,
// so padding cannot bleed in and odd sizes are exact.
//
// Work per band, on `threads` threads:
//   1. reduce: column strips aligned to 2^(levels-1) level-0 pixels are independent through the
//      whole mip chain, so each thread cascades its strip through every level;
//   2. emit: every tile row whose texels are all present is cut (with clamped borders),
//      checksummed and compressed in parallel, then appended to tiles.bin in order.
// The builder writes tiles.bin, index.bin and, in finish(), manifest.json last. The caller
// builds into a temporary directory and renames it, so an interrupted build never looks done.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "pack/format.h"
#include "pack/geometry.h"

namespace gigascroll {

struct PackOptions {
    std::uint32_t tile_size = 128;
    std::uint32_t border = 4;
    Codec codec = Codec::Raw;
    int zstd_level = 3;
    unsigned threads = 0;  // 0 = all cores
};

struct PaintingSpec {
    std::string name;
    std::string source;
    std::string conversion;
    std::uint32_t width = 0, height = 0;
    std::uint32_t table_x = 0, table_y = 0;  // offset in the merged page table
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
    struct Level;
    struct Painting;

    void add_sub_band(const std::uint8_t* rgb, std::uint32_t rows);
    void reduce_strip(std::uint32_t x0, std::uint32_t x1, const std::uint8_t* rgb,
                      std::uint32_t y_begin, std::uint32_t rows);
    void finish_row(std::size_t l, std::uint32_t y, std::uint32_t x0, std::uint32_t x1);
    void emit_ready_tiles();
    void emit_tile_row(Level& lv, std::uint32_t ty);
    void write_all(const void* data, std::size_t size);

    std::string directory_;
    PackOptions options_;
    int fd_ = -1;
    std::uint64_t data_bytes_ = 0;
    std::uint64_t tiles_written_ = 0;
    std::vector<Painting> paintings_;
    std::vector<Level> levels_;   // mip chain state of the painting being built
    bool open_painting_ = false;
    bool finished_ = false;
    std::vector<std::uint8_t> staging_;  // a group of cut tiles before writing (raw codec)
};

}  // namespace gigascroll
