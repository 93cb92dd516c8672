// manifest.json, the pack's description (format in format.h): the one writer (the builder's
// finish()) and the one reader (TilePack, and through it Python), and between them the one
// validator, so a reader refuses exactly what a builder would refuse to write. Written last in
// a build: its presence marks a complete pack.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "pack/format.h"
#include "pack/geometry.h"

namespace gigascroll {

// One painting of a pack: where it came from and its placed geometry.
struct PaintingInfo {
    std::string name;
    std::string source;      // input file (or "array") the painting came from
    std::string conversion;  // how the input was turned into 8-bit RGB
    PaintingGeometry geometry;
    std::string colour;  // JSON object text: source profile, intent, transform; empty if absent
    // An instance of an earlier, stored painting (its index; -1: the painting stores its own
    // tiles): its own name and page-table placement, the source's size, index entries
    // (geometry's first_entry is the source's) and tile data, whose checksums name the
    // source's tiles. Written as "instance_of" only when set, so a pack without instances
    // has the manifest it had before instances existed.
    std::int64_t instance_of = -1;
};

// The painting whose stored tiles painting p reads (p itself unless p is an instance).
inline std::uint32_t tile_source(const std::vector<PaintingInfo>& paintings, std::uint32_t p) {
    const std::int64_t s = paintings[p].instance_of;
    return s < 0 ? p : static_cast<std::uint32_t>(s);
}

struct Manifest {
    std::uint32_t version = kPackVersion;
    std::uint32_t tile_size = 0, border = 0;
    Codec codec = Codec::Raw;
    std::uint64_t tile_count = 0;    // index entries over all paintings
    std::uint64_t tiles_bytes = 0;   // bytes of all tile files together
    std::uint32_t table_width = 0, table_height = 0;  // merged Mc x Nc
    std::string page_table_extra = "{}";  // a JSON object: packer name, fill ratios, ...
    std::vector<PaintingInfo> paintings;
    // Version 2: the tile files a TileEntry::file indexes (plain names inside the pack);
    // version 1: {"tiles.bin"}.
    std::vector<std::string> tile_files;
};

// The merged table may be at most this many times the smallest power-of-two area that could
// hold the paintings' tables (a layout that wastes more is a corrupt or hostile manifest:
// gigabytes of page table for a small painting).
inline constexpr std::uint64_t kMaxTableSlack = 16;

// Everything a reader relies on, in 64-bit arithmetic: version, tile parameters, 1 to
// kMaxPackPaintings paintings, each painting's geometry against its size (placed at the
// running entry total; an instance at its source's entries, with its source's size, its
// source an earlier painting that is no instance), page tables aligned, inside the merged power-of-two table and
// pairwise disjoint, the merged table not absurdly larger than the paintings need, the
// entry total, and (version 2) the tile file names. InvalidArgument naming the field.
void validate_manifest(const Manifest& m);

// The manifest's JSON text (as written to manifest.json), validated first. InvalidArgument
// if it is not valid or page_table_extra / a colour is not a JSON object.
std::string manifest_text(const Manifest& m);
// Writes and fsyncs path. IoError when it cannot.
void write_manifest(const std::string& path, const Manifest& m);
// Parses manifest text with exact types (integers must be JSON integers in range, no floats,
// no wrap-around), then validate_manifest(). InvalidArgument naming the field.
Manifest parse_manifest(const std::string& text);
// Reads and parses path: IoError naming `path` for anything missing, malformed or
// inconsistent. `text_out` (optional) receives the parsed manifest serialised again.
Manifest read_manifest(const std::string& path, std::string* text_out = nullptr);

}  // namespace gigascroll
