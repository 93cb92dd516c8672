// A temporary directory, a random RGB image, and a pack built from an image into a
// directory by the builder, as the pack tests use them.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "pack/builder.h"
#include "pack/geometry.h"

namespace gigascroll {

struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::string tmpl = (std::filesystem::temp_directory_path() / "gigascroll-test-XXXXXX").string();
        path = ::mkdtemp(tmpl.data());
    }
    ~TempDir() { std::filesystem::remove_all(path); }
};

inline std::vector<std::uint8_t> random_image(std::uint32_t w, std::uint32_t h, unsigned seed) {
    std::mt19937 rng(seed);
    std::vector<std::uint8_t> img(std::size_t(w) * h * 3);
    for (auto& v : img) v = static_cast<std::uint8_t>(rng() & 255);
    return img;
}

inline void build(const std::filesystem::path& dir, const std::vector<std::uint8_t>& img,
                  std::uint32_t w, std::uint32_t h, std::uint32_t tile, std::uint32_t border, Codec codec,
                  std::uint32_t band, unsigned threads) {
    PackOptions o;
    o.tile_size = tile;
    o.border = border;
    o.codec = codec;
    o.threads = threads;
    PackBuilder b(dir.string(), o);
    b.begin_painting({"img", "test", "none", w, h, 0, 0});
    for (std::uint32_t y = 0; y < h; y += band)
        b.add_rows(img.data() + std::size_t(y) * w * 3, std::min(band, h - y), w);
    b.end_painting();
    const PaintingGeometry g = PaintingGeometry(w, h, tile, border);
    b.finish(g.page_table_width(), g.page_table_height());
}

}  // namespace gigascroll
