// Read side of a tile pack (format in format.h), versions 1 and 2. Opening parses and
// validates the manifest (the builder's own validator), checks every binary's magic, version
// and size, and maps the index; a lookup is then O(1). A read checks the entry (flags, file,
// bounds) and its checksum, which in version 2 also names the tile. A painting that is an
// instance of another (manifest.h) reads its source's entries and tiles under its own index.
// Thread safety: after construction the object is logically immutable; read_tile uses pread
// on shared descriptors (opened once, lazily past a budget) and per-thread scratch, so
// loader threads may call it concurrently.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <atomic>
#include <string>
#include <vector>

#include "pack/format.h"
#include "pack/geometry.h"
#include "pack/manifest.h"
#include "pack/texel_format.h"

namespace gigascroll {

struct TileLocation {
    std::uint64_t offset;
    std::uint32_t length;
    std::uint64_t checksum;
    std::uint32_t file = 0;  // index into tile_files()
};

class TilePack {
public:
    // IoError: missing/unreadable manifest or binaries, wrong magic or version, truncation,
    // inconsistent geometry.
    explicit TilePack(const std::string& directory);
    ~TilePack();
    TilePack(const TilePack&) = delete;
    TilePack& operator=(const TilePack&) = delete;

    const std::string& directory() const { return directory_; }
    const std::vector<PaintingInfo>& paintings() const { return paintings_; }
    std::uint32_t tile_size() const { return tile_size_; }
    std::uint32_t border() const { return border_; }
    std::uint32_t payload() const { return tile_size_ - 2 * border_; }
    Codec codec() const { return codec_; }
    std::uint32_t table_width() const { return table_width_; }   // merged Mc
    std::uint32_t table_height() const { return table_height_; } // merged Nc
    // The paintings' placed geometry and the merged table: what the runtime needs.
    PackGeometry geometry() const;
    std::uint64_t tile_count() const { return entry_count_; }
    std::size_t tile_bytes() const { return std::size_t(tile_size_) * tile_size_ * 3; }
    // How the cache keeps this pack's tiles (RGB8, or BC1 for a bc1 pack) and the bytes of one
    // tile in that form: what read_slot_tile() writes and the loader delivers.
    TexelFormat slot_format() const { return texel_format_of(codec_); }
    std::size_t slot_bytes() const { return texel_format_tile_bytes(slot_format(), tile_size_); }
    // The manifest as this reader parsed it, serialised again (JSON text).
    const std::string& manifest_json() const { return manifest_json_; }
    std::uint32_t version() const { return version_; }
    const std::vector<std::string>& tile_files() const { return tile_files_; }
    // What a caller should be told about this pack (a version-1 pack cannot detect swapped
    // or duplicated index entries).
    const std::vector<std::string>& warnings() const { return warnings_; }

    // InvalidArgument when p or l is out of range or (tx, ty) lies outside the level's
    // power-of-two page-table grid; false for padding tiles inside that grid (every real
    // tile of a finished pack is stored: a corrupt entry is reported by read_tile).
    bool has_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) const;
    // InvalidArgument for a key that is out of range or not stored; IoError for an entry
    // whose flags are not "stored" or whose file is not in tile_files().
    TileLocation locate(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) const;
    // Reads, decompresses and verifies one tile into out[tile_bytes()] (RGB, row-major).
    // IoError on a bad entry, a short read, a checksum mismatch or a corrupt zstd frame.
    void read_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty,
                   std::uint8_t* out) const;
    // The tile in the cache's form into out[slot_bytes()]: the verified BC1 blocks as stored
    // for a bc1 pack, what read_tile() gives otherwise. The same errors as read_tile().
    void read_slot_tile(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty,
                        std::uint8_t* out) const;

private:
    struct TileFile;
    struct FileHandle;
    // Reads the stored bytes of e into scratch and verifies their length and checksum.
    const std::uint8_t* read_stored(const TileEntry& e, std::uint32_t p, std::uint32_t l,
                                    std::uint32_t tx, std::uint32_t ty, std::uint8_t* into) const;
    void release();
    // The checked entry of a stored tile (InvalidArgument / IoError as for locate).
    TileEntry entry(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) const;
    // The tile file's descriptor; `transient`: the caller must close it (descriptors ran out).
    int file_descriptor(std::uint32_t file, bool& transient) const;

    std::string directory_;
    std::string manifest_json_;
    std::vector<PaintingInfo> paintings_;
    std::uint32_t tile_size_ = 0, border_ = 0;
    Codec codec_ = Codec::Raw;
    std::uint32_t table_width_ = 0, table_height_ = 0;
    std::uint32_t version_ = kPackVersion;
    std::vector<std::string> tile_files_, warnings_;
    std::unique_ptr<TileFile[]> files_;
    mutable std::atomic<std::size_t> cached_fds_{0};  // descriptors held in files_
    void* index_map_ = nullptr;
    std::size_t index_map_size_ = 0;
    const TileEntry* entries_ = nullptr;
    std::uint64_t entry_count_ = 0;
};

}  // namespace gigascroll
