// On-disk format of a tile pack: a directory holding
//   manifest.json  geometry, paintings, merged page-table layout (written last: its presence
//                  marks a complete pack),
//   tiles.bin      FileHeader + the stored tiles back to back,
//   index.bin      FileHeader + one TileEntry per real tile, per painting, per level, row-major
//                  over that level's real tile grid, so a lookup is one multiply-add.
// All integers are little-endian (the only byte order we build for).
#pragma once
#include <cstdint>
#include <string>

namespace gigascroll {

inline constexpr std::uint32_t kPackVersion = 1;
inline constexpr char kTilesMagic[8] = {'G', 'S', 'T', 'I', 'L', 'E', 'S', '\0'};
inline constexpr char kIndexMagic[8] = {'G', 'S', 'I', 'N', 'D', 'E', 'X', '\0'};
inline constexpr const char* kManifestName = "manifest.json";
inline constexpr const char* kTilesName = "tiles.bin";
inline constexpr const char* kIndexName = "index.bin";
inline constexpr const char* kManifestFormat = "gigascroll-pack";

// 32 bytes at the start of tiles.bin and index.bin.
struct FileHeader {
    char magic[8];
    std::uint32_t version;
    std::uint32_t entry_size;   // index.bin: sizeof(TileEntry); tiles.bin: 0
    std::uint64_t count;        // index.bin: number of entries; tiles.bin: number of tiles
    std::uint64_t data_bytes;   // bytes after the header (lets a reader detect truncation)
};
static_assert(sizeof(FileHeader) == 32);

enum TileFlags : std::uint32_t {
    kTileStored = 1u,  // every entry of a finished pack has it; 0 marks a hole
};

// One stored tile: `length` bytes at `offset` in tiles.bin (offset counts from the file start).
// `checksum` is XXH3-64 of those stored bytes (compressed bytes for zstd).
struct TileEntry {
    std::uint64_t offset;
    std::uint32_t length;
    std::uint32_t flags;
    std::uint64_t checksum;
};
static_assert(sizeof(TileEntry) == 24);

// Bc1: DXT1 blocks (pack/bc1.h), kept block-compressed in the cache.
enum class Codec : std::uint32_t { Raw = 0, Zstd = 1, Bc1 = 2 };

// IoError unless path is a regular file: a FIFO, device or directory in a pack's place would
// block a reader's open() or read forever, or read as garbage.
void require_regular_file(const std::string& path);

// "raw" / "zstd" / "bc1"; InvalidArgument for anything else.
Codec parse_codec(const std::string& name);
const char* codec_name(Codec codec);

}  // namespace gigascroll
