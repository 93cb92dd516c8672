// manifest.json, the pack's description (format in format.h): the one writer (the builder's
// finish()) and the one reader (TilePack, and through it Python), so both apply the same
// rules. Written last in a build: its presence marks a complete pack.
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
};

struct Manifest {
    std::uint32_t version = kPackVersion;
    std::uint32_t tile_size = 0, border = 0;
    Codec codec = Codec::Raw;
    std::uint64_t tile_count = 0;    // index entries over all paintings
    std::uint64_t tiles_bytes = 0;   // size of tiles.bin
    std::uint32_t table_width = 0, table_height = 0;  // merged Mc x Nc
    std::string page_table_extra = "{}";  // a JSON object: packer name, fill ratios, ...
    std::vector<PaintingInfo> paintings;
};

// The manifest's JSON text (as written to manifest.json). InvalidArgument if
// page_table_extra is not a JSON object.
std::string manifest_text(const Manifest& m);
// Writes and fsyncs path. IoError when it cannot.
void write_manifest(const std::string& path, const Manifest& m);
// Parses and checks a manifest: format, version, tile parameters, codec, every painting's
// geometry against its size, the page-table placements and the tile totals. IoError naming
// `path` for anything missing, malformed or inconsistent. `text_out` (optional) receives the
// parsed manifest serialised again.
Manifest read_manifest(const std::string& path, std::string* text_out = nullptr);

}  // namespace gigascroll
