// On-disk format of a tile pack, version 2 (version 1 is still read): a directory holding
//   manifest.json    geometry, paintings, merged page-table layout and the list of tile files
//                    ("tile_files"); written last: its presence marks a complete pack;
//   tiles-NNNNN.bin  one per painting (a build shard): FileHeader + that painting's stored
//                    tiles back to back, so a sharded build merges without copying tile data;
//   index.bin        FileHeader + one TileEntry per real tile, per painting, per level,
//                    row-major over that level's real tile grid, so a lookup is one
//                    multiply-add.
// A version-2 entry's checksum is XXH3-64 of the stored bytes seeded with the tile's
// TileKey::packed() (pack/tile_key.h) XOR kTileSeedSalt, so an entry that was swapped with or
// copied over another tile's fails its check (the salt keeps tile (0, 0, 0, 0)'s seed from
// being 0, which is the unseeded hash). Version 1 has one tiles.bin, entries {offset, length,
// u32 flags, checksum} and unseeded checksums (it cannot detect swapped entries).
// All integers are little-endian (the only byte order we build for).
#pragma once
#include <cstdint>
#include <string>

namespace gigascroll {

inline constexpr std::uint32_t kPackVersion = 2;        // what the builder writes
inline constexpr std::uint32_t kOldestPackVersion = 1;  // the oldest the reader accepts
inline constexpr char kTilesMagic[8] = {'G', 'S', 'T', 'I', 'L', 'E', 'S', '\0'};
inline constexpr char kIndexMagic[8] = {'G', 'S', 'I', 'N', 'D', 'E', 'X', '\0'};
inline constexpr const char* kManifestName = "manifest.json";
inline constexpr const char* kTilesName = "tiles.bin";  // version 1's single tile file
inline constexpr const char* kIndexName = "index.bin";
inline constexpr const char* kManifestFormat = "gigascroll-pack";
// The painting field of TileKey::packed() is 16 bits: a pack holds at most 2^16 paintings
// (and so at most 2^16 tile files, the range of TileEntry::file).
inline constexpr std::uint32_t kMaxPackPaintings = 1u << 16;

// 32 bytes at the start of every tile file and of index.bin.
struct FileHeader {
    char magic[8];
    std::uint32_t version;
    std::uint32_t entry_size;   // index.bin: sizeof(TileEntry); tile files: 0
    std::uint64_t count;        // index.bin: number of entries; tile files: number of tiles
    std::uint64_t data_bytes;   // bytes after the header (lets a reader detect truncation)
};
static_assert(sizeof(FileHeader) == 32);

// The only flag value of a finished pack; a reader refuses every other value.
inline constexpr std::uint16_t kTileStored = 1u;

// One stored tile: `length` bytes at `offset` (from the file start) in tile file `file` (an
// index into the manifest's "tile_files"). `checksum`: see above (compressed bytes for zstd).
// Version 1's u32 flags read as flags (low half) and file (high half, always 0).
struct TileEntry {
    std::uint64_t offset;
    std::uint32_t length;
    std::uint16_t flags;
    std::uint16_t file;
    std::uint64_t checksum;
};
static_assert(sizeof(TileEntry) == 24);

// Bc1: DXT1 blocks (pack/bc1.h), kept block-compressed in the cache.
enum class Codec : std::uint32_t { Raw = 0, Zstd = 1, Bc1 = 2 };

inline constexpr std::uint64_t kTileSeedSalt = 0x9E3779B97F4A7C15ull;  // no valid key: level 121

// The tile file of painting `painting` in a version-2 pack: "tiles-00042.bin".
std::string tile_file_name(std::uint32_t painting);
// Whether a manifest's tile file name is a plain file name (no directory part, no leading
// dot): a manifest must not point a reader outside its pack.
bool is_plain_file_name(const std::string& name);

// The checksum an entry of a pack of `version` stores for these bytes of tile `packed_key`.
std::uint64_t tile_checksum(std::uint32_t version, std::uint64_t packed_key, const void* data,
                            std::size_t size);

// IoError unless path is a regular file: a FIFO, device or directory in a pack's place would
// block a reader's open() or read forever, or read as garbage.
void require_regular_file(const std::string& path);

// "raw" / "zstd" / "bc1"; InvalidArgument for anything else.
Codec parse_codec(const std::string& name);
const char* codec_name(Codec codec);

}  // namespace gigascroll
