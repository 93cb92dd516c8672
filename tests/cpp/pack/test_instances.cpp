// Pack instances: a painting that shares a stored painting's tiles reads them under its own
// index (the checksums name the source's tiles), and the manifest's rules on instances hold
// in the one validator.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "common/error.h"
#include "pack/manifest.h"
#include "pack/reader.h"
#include "temp_pack.h"

namespace gigascroll {
namespace {

// Two stored paintings (24 x 16 and 10 x 10, 8-texel tiles) side by side and an instance
// of the first: its own page table at x = 8.
void build_with_instance(const std::filesystem::path& dir, const std::vector<std::uint8_t>& a,
                         const std::vector<std::uint8_t>& b) {
    PackOptions o;
    o.tile_size = 8;
    o.border = 1;
    PackBuilder builder(dir.string(), o);
    builder.begin_painting({"a", "", "", 24, 16, 0, 0});
    builder.add_rows(a.data(), 16, 24);
    builder.end_painting();
    builder.begin_painting({"b", "", "", 10, 10, 4, 0});
    builder.add_rows(b.data(), 10, 10);
    builder.end_painting();
    PaintingSpec copy{"a-copy", "", "", 0, 0, 8, 0};
    copy.instance_of = 0;
    builder.add_instance(copy);
    builder.finish(16, 4);
}

TEST(PackInstances, AnInstanceReadsItsSourcesTiles) {
    TempDir dir;
    const auto a = random_image(24, 16, 1), b = random_image(10, 10, 2);
    build_with_instance(dir.path, a, b);
    TilePack pack(dir.path.string());
    ASSERT_EQ(pack.paintings().size(), 3u);
    const PaintingInfo& copy = pack.paintings()[2];
    EXPECT_EQ(copy.instance_of, 0);
    EXPECT_EQ(copy.geometry.table_x(), 8u);
    EXPECT_EQ(copy.geometry.first_entry(), 0u);
    EXPECT_EQ(pack.tile_count(), pack.paintings()[0].geometry.total_tiles() +
                                     pack.paintings()[1].geometry.total_tiles());
    std::vector<std::uint8_t> x(pack.tile_bytes()), y(pack.tile_bytes());
    const PaintingGeometry& g = copy.geometry;
    for (std::uint32_t l = 0; l < g.levels(); ++l)
        for (std::uint32_t ty = 0; ty < g.tiles_y(l); ++ty)
            for (std::uint32_t tx = 0; tx < g.tiles_x(l); ++tx) {
                pack.read_tile(0, l, tx, ty, x.data());
                pack.read_tile(2, l, tx, ty, y.data());
                EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size()), 0);
            }
}

TEST(PackInstances, TheValidatorRefusesBadInstances) {
    TempDir dir;
    build_with_instance(dir.path, random_image(24, 16, 1), random_image(10, 10, 2));
    const Manifest good = read_manifest((dir.path / "manifest.json").string());
    EXPECT_NO_THROW(validate_manifest(good));
    auto refused = [&](auto edit) {
        Manifest m = good;
        edit(m);
        EXPECT_THROW(validate_manifest(m), InvalidArgument);
    };
    refused([](Manifest& m) { m.paintings[2].instance_of = 2; });  // itself
    refused([](Manifest& m) { m.paintings[2].instance_of = 1; });  // another size
    refused([](Manifest& m) { m.paintings[2].instance_of = -1; });  // its own entries missing
    refused([](Manifest& m) { m.paintings[1].instance_of = 0; });  // a stored one tagged
    refused([](Manifest& m) { m.version = 1; m.tile_files = {"tiles.bin"}; });
}

TEST(PackInstances, TheBuilderKeepsInstancesLast) {
    TempDir dir;
    PackOptions o;
    o.tile_size = 8;
    o.border = 1;
    PackBuilder builder(dir.path.string(), o);
    PaintingSpec copy{"c", "", "", 0, 0, 8, 0};
    copy.instance_of = 0;
    EXPECT_THROW(builder.add_instance(copy), InvalidArgument);  // no stored painting yet
    const auto a = random_image(4, 4, 3);
    builder.begin_painting({"a", "", "", 4, 4, 0, 0});
    builder.add_rows(a.data(), 4, 4);
    builder.end_painting();
    builder.add_instance(copy);
    EXPECT_THROW(builder.begin_painting({"b", "", "", 4, 4, 1, 0}), InvalidArgument);
}

}  // namespace
}  // namespace gigascroll
