// The one manifest validator (builder and reader), format v2's key-bound checksums and entry
// checks: every hostile value the issue lists is refused naming its field, checked against
// hand-made manifests whose right answer is known.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <cstring>
#include <thread>
#include <string>
#include <vector>

#include "common/checksum.h"
#include "common/error.h"
#include "pack/manifest.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"
#include "pack/tile_key.h"

using namespace gigascroll;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// A pack of two paintings built by the builder: its manifest is the reference valid one.
struct TwoPaintings {
    TempDir dir;
    TwoPaintings() {
        PackOptions o;
        o.tile_size = 16;
        o.border = 2;
        PackBuilder b(dir.path.string(), o);
        const auto a = random_image(40, 30, 1), c = random_image(20, 20, 2);
        b.begin_painting({"a", "test", "none", 40, 30, 0, 0});
        b.add_rows(a.data(), 30, 40);
        b.end_painting();
        b.begin_painting({"c", "test", "none", 20, 20, 4, 0});  // a's table is 4 x 4
        b.add_rows(c.data(), 20, 20);
        b.end_painting();
        b.finish(8, 4);
    }
    json manifest() const {
        std::ifstream in(dir.path / kManifestName);
        return json::parse(in);
    }
};

std::string refusal(const json& m) {
    try {
        (void)parse_manifest(m.dump());
    } catch (const InvalidArgument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Manifest, TheBuildersManifestParsesBackEqual) {
    TwoPaintings p;
    const Manifest m = parse_manifest(p.manifest().dump());
    EXPECT_EQ(m.version, 2u);
    ASSERT_EQ(m.paintings.size(), 2u);
    EXPECT_EQ(m.tile_files, (std::vector<std::string>{"tiles-00000.bin", "tiles-00001.bin"}));
    EXPECT_EQ(m.paintings[1].geometry.table_x(), 4u);
    EXPECT_EQ(m.tiles_bytes, fs::file_size(p.dir.path / "tiles-00000.bin") +
                                 fs::file_size(p.dir.path / "tiles-00001.bin"));
}

TEST(Manifest, HostileValuesAreRefusedNamingTheField) {
    TwoPaintings p;
    const json good = p.manifest();
    ASSERT_EQ(refusal(good), "");
    struct Case {
        const char* what;
        void (*mutate)(json&);
        const char* field;
    };
    const Case cases[] = {
        {"border 2^31 (2 * border wraps to 0 in 32 bits)", [](json& m) { m["border"] = 1ull << 31; }, "border"},
        {"width above 2^32 (read modulo 2^32 = 40)", [](json& m) { m["paintings"][0]["width"] = (1ull << 32) + 40; }, "paintings[0].width"},
        {"a float as an integer", [](json& m) { m["tile_size"] = 16.0; }, "tile_size"},
        {"version 1.9", [](json& m) { m["version"] = 1.9; }, "version"},
        {"version 3", [](json& m) { m["version"] = 3; }, "version 3"},
        {"negative offset", [](json& m) { m["paintings"][1]["page_table"]["x"] = -4; }, "paintings[1].page_table.x"},
        {"boolean", [](json& m) { m["paintings"][0]["height"] = true; }, "paintings[0].height"},
        {"non-power-of-two merged table", [](json& m) { m["page_table"]["width"] = 12; }, "page_table.width"},
        {"absurd merged table", [](json& m) { m["page_table"]["width"] = 1 << 20; m["page_table"]["height"] = 1 << 20; }, "absurdly large"},
        {"overlapping page tables", [](json& m) { m["paintings"][1]["page_table"]["x"] = 2; }, "overlap"},
        {"first_entry off by one", [](json& m) { m["paintings"][1]["first_entry"] = m["paintings"][1]["first_entry"].get<int>() + 1; }, "paintings[1].first_entry"},
        {"a level's width", [](json& m) { m["paintings"][0]["levels"][1]["width"] = 7; }, "paintings[0].levels[1]"},
        {"uv_scale", [](json& m) { m["paintings"][0]["uv_scale"][0] = 0.5; }, "paintings[0].uv_scale"},
        {"tile file outside the pack", [](json& m) { m["tile_files"][1] = "../tiles-00001.bin"; }, "tile_files[1]"},
        {"tile file listed twice", [](json& m) { m["tile_files"][1] = "tiles-00000.bin"; }, "tile_files[1]"},
        {"v1 with tile_files", [](json& m) { m["version"] = 1; }, "tile_files"},
        {"no tiles_bytes in v2", [](json& m) { m.erase("tiles_bytes"); }, "tiles_bytes"},
        {"tile_count", [](json& m) { m["tile_count"] = 1; }, "tile_count"},
        {"packer", [](json& m) { m["page_table"]["packer"] = 3; }, "page_table.packer"},
    };
    for (const Case& c : cases) {
        json m = good;
        c.mutate(m);
        const std::string why = refusal(m);
        EXPECT_NE(why.find(c.field), std::string::npos) << c.what << ": got '" << why << "'";
    }
    // The reader refuses the same with IoError naming the file.
    json m = good;
    m["border"] = 1ull << 31;
    std::ofstream(p.dir.path / kManifestName) << m.dump();
    try {
        TilePack pack(p.dir.path.string());
        ADD_FAILURE() << "a border of 2^31 opened";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("manifest.json"), std::string::npos);
    }
}

TEST(Manifest, DeeplyNestedJsonIsRefusedNotRecursedInto) {
    TwoPaintings p;
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    std::string text = p.manifest().dump();
    text.insert(text.find("\"page_table\":{") + 14, "\"junk\":" + deep + ",");
    EXPECT_THROW(parse_manifest(text), InvalidArgument);
}

// The tile key's painting field is 16 bits: 2^16 paintings are fine, one more is refused.
TEST(Manifest, PaintingCountAtTheTileKeysBoundary) {
    auto make = [](std::uint32_t n) {
        Manifest m;
        m.tile_size = 4;
        m.border = 1;
        const std::uint32_t side = 512;  // 512 x 512 one-entry tables hold 2^18 paintings
        m.table_width = m.table_height = side;
        for (std::uint32_t i = 0; i < n; ++i) {
            PaintingInfo p;
            p.name = "p" + std::to_string(i);
            p.geometry = PaintingGeometry(2, 2, 4, 1);  // one tile, one level, a 1 x 1 table
            p.geometry.place(i % side, i / side, i);
            m.paintings.push_back(std::move(p));
            m.tile_files.push_back(tile_file_name(i));
        }
        m.tile_count = n;
        return m;
    };
    Manifest m = make(kMaxPackPaintings);
    m.table_width = m.table_height = 256;  // exactly 2^16 entries
    for (std::uint32_t i = 0; i < kMaxPackPaintings; ++i) m.paintings[i].geometry.place(i % 256, i / 256, i);
    EXPECT_NO_THROW(validate_manifest(m));
    // The last painting's keys stay distinct from painting 0's; one more would alias.
    const std::uint64_t key0 = TileKey{0, 0, 0, 0}.packed();
    EXPECT_NE((TileKey{kMaxPackPaintings - 1, 0, 0, 0}.packed()), key0);
    EXPECT_EQ((TileKey{kMaxPackPaintings, 0, 0, 0}.packed()), key0);
    const Manifest over = make(kMaxPackPaintings + 1);
    try {
        validate_manifest(over);
        ADD_FAILURE() << "2^16 + 1 paintings accepted";
    } catch (const InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find("16-bit painting field"), std::string::npos) << e.what();
    }
    // The builder refuses to begin painting 2^16 (whose key would alias painting 0).
    TempDir dir;
    PackOptions o;
    o.tile_size = 4;
    o.border = 1;
    PackBuilder last(dir.path.string(), o, kMaxPackPaintings - 1);
    const auto img = random_image(2, 2, 3);
    last.begin_painting({"last", "", "", 2, 2, 0, 0});
    last.add_rows(img.data(), 2, 2);
    last.end_painting();
    EXPECT_THROW(last.begin_painting({"one too many", "", "", 2, 2, 0, 0}), InvalidArgument);
    EXPECT_THROW(PackBuilder(dir.path.string(), o, kMaxPackPaintings), InvalidArgument);
}

namespace {
void rewrite_entry(const fs::path& index, std::uint64_t i, const TileEntry& e) {
    std::fstream f(index, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(sizeof(FileHeader) + i * sizeof(TileEntry)));
    f.write(reinterpret_cast<const char*>(&e), sizeof e);
}
TileEntry read_entry(const fs::path& index, std::uint64_t i) {
    std::ifstream f(index, std::ios::binary);
    f.seekg(static_cast<std::streamoff>(sizeof(FileHeader) + i * sizeof(TileEntry)));
    TileEntry e{};
    f.read(reinterpret_cast<char*>(&e), sizeof e);
    return e;
}
}  // namespace

TEST(Manifest, ChecksumsAreBoundToTheirTileKeys) {
    TwoPaintings p;
    const fs::path index = p.dir.path / kIndexName;
    // Entry 0 is (0, 0, 0, 0); entry 1 is (0, 0, 1, 0). The checksum is XXH3 seeded with the
    // salted key (an independent XXH3 call here).
    const TileEntry e0 = read_entry(index, 0), e1 = read_entry(index, 1);
    {
        std::ifstream f(p.dir.path / "tiles-00000.bin", std::ios::binary);
        std::vector<char> bytes(e0.length);
        f.seekg(static_cast<std::streamoff>(e0.offset));
        f.read(bytes.data(), e0.length);
        EXPECT_EQ(e0.checksum, checksum64(bytes.data(), bytes.size(), TileKey{0, 0, 0, 0}.packed() ^ kTileSeedSalt));
        EXPECT_NE(e0.checksum, checksum64(bytes.data(), bytes.size()));
    }
    std::vector<std::uint8_t> out(16 * 16 * 3);
    rewrite_entry(index, 0, e1);  // swapped
    rewrite_entry(index, 1, e0);
    {
        TilePack pack(p.dir.path.string());
        EXPECT_THROW(pack.read_tile(0, 0, 0, 0, out.data()), IoError);
        EXPECT_THROW(pack.read_tile(0, 0, 1, 0, out.data()), IoError);
    }
    rewrite_entry(index, 0, e0);
    rewrite_entry(index, 1, e0);  // duplicated
    {
        TilePack pack(p.dir.path.string());
        EXPECT_NO_THROW(pack.read_tile(0, 0, 0, 0, out.data()));
        EXPECT_THROW(pack.read_tile(0, 0, 1, 0, out.data()), IoError);
    }
    rewrite_entry(index, 1, e1);
    for (const std::uint16_t flags : {0, 2, 3, 0x8001}) {  // anything but "stored"
        TileEntry bad = e1;
        bad.flags = flags;
        rewrite_entry(index, 1, bad);
        TilePack pack(p.dir.path.string());
        EXPECT_TRUE(pack.has_tile(0, 0, 1, 0));  // geometry says it is a real tile ...
        EXPECT_THROW(pack.read_tile(0, 0, 1, 0, out.data()), IoError) << flags;  // ... the entry is corrupt
        EXPECT_THROW(pack.locate(0, 0, 1, 0), IoError);
    }
    TileEntry bad = e1;
    bad.file = 7;  // not in tile_files
    rewrite_entry(index, 1, bad);
    {
        TilePack pack(p.dir.path.string());
        EXPECT_THROW(pack.read_tile(0, 0, 1, 0, out.data()), IoError);
    }
    bad = e1;
    bad.offset = ~std::uint64_t(0) - 10;  // offset + length wraps in 64 bits
    rewrite_entry(index, 1, bad);
    {
        TilePack pack(p.dir.path.string());
        EXPECT_THROW(pack.read_tile(0, 0, 1, 0, out.data()), IoError);
    }
}

// 600 paintings: 600 tile files, more than the reader keeps open (64 from the start, 512 at
// most): every tile still reads back right, from two threads at once.
TEST(Manifest, PacksWithMoreTileFilesThanCachedDescriptors) {
    TempDir dir;
    PackOptions o;
    o.tile_size = 4;
    o.border = 1;
    const std::uint32_t n = 600, side = 32;  // 1 x 1 tables on a 32 x 32 grid
    std::vector<std::vector<std::uint8_t>> images;
    {
        PackBuilder b(dir.path.string(), o);
        for (std::uint32_t i = 0; i < n; ++i) {
            images.push_back(random_image(2, 2, 100 + i));
            b.begin_painting({"p" + std::to_string(i), "", "", 2, 2, i % side, i / side});
            b.add_rows(images.back().data(), 2, 2);
            b.end_painting();
        }
        b.finish(side, side);
    }
    const TilePack pack(dir.path.string());
    ASSERT_EQ(pack.tile_files().size(), n);
    std::vector<int> bad(2, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 2; ++t)
        threads.emplace_back([&, t] {
            std::vector<std::uint8_t> out(4 * 4 * 3);
            for (int rep = 0; rep < 2; ++rep)
                for (std::uint32_t i = t; i < n; i += 1) {
                    pack.read_tile(i, 0, 0, 0, out.data());
                    // Texel (1, 1) of the tile is pixel (0, 0) of the 2 x 2 image.
                    bad[t] += std::memcmp(&out[(1 * 4 + 1) * 3], images[i].data(), 3) != 0;
                }
        });
    for (auto& th : threads) th.join();
    EXPECT_EQ(bad[0] + bad[1], 0);
}
