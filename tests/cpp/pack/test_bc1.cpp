// BC1 tiles against libsquish's own decoder (bit for bit, on random blocks of both palette
// modes and on blocks libsquish encoded), and a bc1 pack against the raw pack of the same
// image: its stored blocks are the encoding of the raw tile, read_tile is their decoding, and
// the borders neighbouring tiles share decode to the same bytes (seamless filtering).
#include <gtest/gtest.h>
#include <squish.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "common/error.h"
#include "pack/bc1.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"

using namespace gigascroll;

namespace {

// libsquish's decoding of one block as RGB (its alpha is dropped: the cache keeps RGB).
void squish_decode(const std::uint8_t* block, std::uint8_t* rgb16) {
    squish::u8 rgba[64];
    squish::Decompress(rgba, block, squish::kDxt1);
    for (int i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) rgb16[3 * i + c] = rgba[4 * i + c];
}

// A smooth image with some edges: the content BC1 is made for (and random noise for the rest).
std::vector<std::uint8_t> painting_like(std::uint32_t w, std::uint32_t h, unsigned seed) {
    std::mt19937 rng(seed);
    std::vector<std::uint8_t> img(std::size_t(w) * h * 3);
    for (std::uint32_t y = 0; y < h; ++y)
        for (std::uint32_t x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const int v = int(128 + 100 * std::sin(0.05 * x * (c + 1) + 0.03 * y)) +
                              ((x / 17 + y / 13) % 5 == 0 ? 60 : 0) + int(rng() % 9) - 4;
                img[(std::size_t(y) * w + x) * 3 + c] = std::uint8_t(std::clamp(v, 0, 255));
            }
    return img;
}

}  // namespace

TEST(Bc1, DecodesRandomBlocksLikeLibsquish) {
    std::mt19937 rng(7);
    std::uint8_t block[8], ours[48], theirs[48];
    int three_colour = 0;
    for (int n = 0; n < 200000; ++n) {
        for (auto& b : block) b = std::uint8_t(rng());
        if (n % 7 == 0) block[2] = block[0], block[3] = block[1];  // c0 == c1: 3-colour mode
        three_colour += (block[0] | block[1] << 8) <= (block[2] | block[3] << 8);
        for (unsigned py = 0; py < 4; ++py)
            for (unsigned px = 0; px < 4; ++px) bc1_decode_texel(block, px, py, ours + 3 * (py * 4 + px));
        squish_decode(block, theirs);
        ASSERT_EQ(0, std::memcmp(ours, theirs, 48)) << "block " << n;
    }
    EXPECT_GT(three_colour, 50000);  // both palette modes were exercised
}

TEST(Bc1, EncodedTileDecodesLikeLibsquish) {
    constexpr std::uint32_t T = 64;
    const auto img = painting_like(T, T, 3);
    for (Bc1Fit fit : {Bc1Fit::Range, Bc1Fit::Cluster}) {
    std::vector<std::uint8_t> blocks(bc1_tile_bytes(T)), ours(T * T * 3);
    bc1_encode_tile(img.data(), T, blocks.data(), fit);
    bc1_decode_tile(blocks.data(), T, ours.data());
    double se = 0;
    for (std::uint32_t by = 0; by < T / 4; ++by)
        for (std::uint32_t bx = 0; bx < T / 4; ++bx) {
            std::uint8_t theirs[48];
            squish_decode(blocks.data() + (by * (T / 4) + bx) * 8, theirs);
            for (int py = 0; py < 4; ++py)
                for (int px = 0; px < 4; ++px)
                    for (int c = 0; c < 3; ++c)
                        ASSERT_EQ(ours[((by * 4 + py) * T + bx * 4 + px) * 3 + c], theirs[(py * 4 + px) * 3 + c]);
        }
    for (std::size_t i = 0; i < img.size(); ++i) se += (double(ours[i]) - img[i]) * (ours[i] - img[i]);
    const double psnr = 10 * std::log10(255.0 * 255.0 / (se / img.size()));
    EXPECT_GT(psnr, 30.0);  // a working encoder, not just a decodable one
    }
    EXPECT_THROW(parse_bc1_fit("best"), InvalidArgument);
}

TEST(Bc1, PackStoresTheEncodingOfTheRawTilesAndSeamsAgree) {
    constexpr std::uint32_t W = 157, H = 101, T = 32, E = 4;  // P = 24
    const auto img = painting_like(W, H, 11);
    TempDir raw_dir, bc1_dir;
    build(raw_dir.path, img, W, H, T, E, Codec::Raw, 37, 2);
    build(bc1_dir.path, img, W, H, T, E, Codec::Bc1, 37, 2);
    TilePack raw(raw_dir.path.string()), bc1(bc1_dir.path.string());
    ASSERT_EQ(bc1.codec(), Codec::Bc1);
    EXPECT_EQ(bc1.slot_format(), TexelFormat::Bc1);
    EXPECT_EQ(bc1.slot_bytes(), T * T / 2);
    EXPECT_EQ(raw.slot_bytes() / bc1.slot_bytes(), 6u);  // 24 bits per texel against 4
    const PaintingGeometry& g = bc1.paintings()[0].geometry;
    const std::uint32_t P = T - 2 * E;
    std::vector<std::uint8_t> rgb(T * T * 3), blocks(bc1.slot_bytes()), expect(bc1.slot_bytes()),
        decoded(T * T * 3), right(T * T * 3), below(T * T * 3);
    for (std::uint32_t l = 0; l < g.levels(); ++l)
        for (std::uint32_t ty = 0; ty < g.tiles_y(l); ++ty)
            for (std::uint32_t tx = 0; tx < g.tiles_x(l); ++tx) {
                raw.read_tile(0, l, tx, ty, rgb.data());
                bc1_encode_tile(rgb.data(), T, expect.data());
                bc1.read_slot_tile(0, l, tx, ty, blocks.data());
                ASSERT_EQ(blocks, expect);
                bc1.read_tile(0, l, tx, ty, decoded.data());
                std::vector<std::uint8_t> ref(T * T * 3);
                bc1_decode_tile(expect.data(), T, ref.data());
                ASSERT_EQ(decoded, ref);
                // Shared borders: this tile's columns [P, T) are the right neighbour's [0, 2E),
                // its rows [P, T) the lower neighbour's [0, 2E), texel for texel after decoding.
                if (tx + 1 < g.tiles_x(l)) {
                    bc1.read_tile(0, l, tx + 1, ty, right.data());
                    for (std::uint32_t j = 0; j < T; ++j)
                        ASSERT_EQ(0, std::memcmp(&decoded[(j * T + P) * 3], &right[(j * T) * 3], 2 * E * 3));
                }
                if (ty + 1 < g.tiles_y(l)) {
                    bc1.read_tile(0, l, tx, ty + 1, below.data());
                    for (std::uint32_t j = 0; j < 2 * E; ++j)
                        ASSERT_EQ(0, std::memcmp(&decoded[((P + j) * T) * 3], &below[(j * T) * 3], T * 3));
                }
            }
}

TEST(Bc1, RejectsTilesBlocksCannotCover) {
    TempDir dir;
    PackOptions o;
    o.codec = Codec::Bc1;
    o.tile_size = 30;  // not a multiple of 4
    o.border = 3;
    EXPECT_THROW(PackBuilder(dir.path.string(), o), InvalidArgument);
    o.tile_size = 32;  // payload 26
    EXPECT_THROW(PackBuilder(dir.path.string(), o), InvalidArgument);
    EXPECT_EQ(parse_codec("bc1"), Codec::Bc1);
    EXPECT_STREQ(codec_name(Codec::Bc1), "bc1");
}
