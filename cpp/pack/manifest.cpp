#include "pack/manifest.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace gigascroll {

using nlohmann::json;

std::string manifest_text(const Manifest& mf) {
    json extra;
    try {
        extra = json::parse(mf.page_table_extra);
    } catch (const json::exception& e) {
        throw InvalidArgument(std::string("page_table_json: ") + e.what());
    }
    require(extra.is_object(), "page_table_json must be a JSON object");
    json m;
    m["format"] = kManifestFormat;
    m["version"] = mf.version;
    m["tile_size"] = mf.tile_size;
    m["border"] = mf.border;
    m["payload"] = mf.tile_size - 2 * mf.border;
    m["codec"] = codec_name(mf.codec);
    m["tile_count"] = mf.tile_count;
    m["tiles_bytes"] = mf.tiles_bytes;
    json pt = extra;
    pt["width"] = mf.table_width;
    pt["height"] = mf.table_height;
    m["page_table"] = pt;
    m["paintings"] = json::array();
    for (const auto& p : mf.paintings) {
        const PaintingGeometry& g = p.geometry;
        json jp;
        jp["name"] = p.name;
        jp["source"] = p.source;
        jp["conversion"] = p.conversion;
        if (!p.colour.empty()) {
            json colour;
            try {
                colour = json::parse(p.colour);
            } catch (const json::exception& e) {
                throw InvalidArgument("colour of painting '" + p.name + "': " + e.what());
            }
            require(colour.is_object(), "colour of painting '" + p.name + "' must be a JSON object");
            jp["colour"] = std::move(colour);
        }
        jp["width"] = g.width();
        jp["height"] = g.height();
        jp["uv_scale"] = {g.uv_scale_u(), g.uv_scale_v()};
        jp["page_table"] = {{"width", g.page_table_width()}, {"height", g.page_table_height()},
                            {"x", g.table_x()}, {"y", g.table_y()}};
        jp["first_entry"] = g.first_entry();
        jp["tile_count"] = g.total_tiles();
        jp["levels"] = json::array();
        for (std::uint32_t l = 0; l < g.levels(); ++l) {
            const LevelGeometry& lv = g.level(l);
            jp["levels"].push_back({{"level", l}, {"width", lv.width}, {"height", lv.height},
                                    {"tiles_x", lv.tiles_x}, {"tiles_y", lv.tiles_y},
                                    {"first_entry", lv.first_tile}});
        }
        m["paintings"].push_back(std::move(jp));
    }
    return m.dump(2) + '\n';
}

void write_manifest(const std::string& path, const Manifest& m) {
    const std::string text = manifest_text(m);
    {
        std::ofstream out(path, std::ios::trunc);
        out << text;
        out.flush();
        if (!out) throw IoError(path + ": write failed");
    }
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        ::fsync(fd);
        ::close(fd);
    }
}

Manifest read_manifest(const std::string& path, std::string* text_out) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        throw IoError(path + ": missing manifest (not a finished tile pack)");
    require_regular_file(path);
    std::ifstream in(path);
    if (!in) throw IoError(path + ": cannot read the manifest");
    json m;
    try {
        m = json::parse(in);
    } catch (const json::exception& e) {
        throw IoError(path + ": corrupt manifest: " + e.what());
    }
    Manifest mf;
    try {
        if (m.at("format").get<std::string>() != kManifestFormat)
            throw IoError(path + ": not a gigascroll pack manifest");
        mf.version = m.at("version").get<std::uint32_t>();
        if (mf.version != kPackVersion)
            throw IoError(path + ": unsupported pack version " + std::to_string(mf.version));
        mf.tile_size = m.at("tile_size").get<std::uint32_t>();
        mf.border = m.at("border").get<std::uint32_t>();
        check_tile_parameters(mf.tile_size, mf.border);
        mf.codec = parse_codec(m.at("codec").get<std::string>());
        mf.table_width = m.at("page_table").at("width").get<std::uint32_t>();
        mf.table_height = m.at("page_table").at("height").get<std::uint32_t>();
        mf.tiles_bytes = m.value("tiles_bytes", std::uint64_t(0));
        std::uint64_t entries = 0;
        for (const auto& jp : m.at("paintings")) {
            PaintingInfo info;
            info.name = jp.at("name").get<std::string>();
            info.source = jp.value("source", std::string());
            info.conversion = jp.value("conversion", std::string());
            if (jp.contains("colour")) {
                if (!jp.at("colour").is_object())
                    throw IoError(path + ": colour of painting '" + info.name +
                                  "' is not a JSON object");
                info.colour = jp.at("colour").dump();
            }
            PaintingGeometry g(jp.at("width").get<std::uint32_t>(), jp.at("height").get<std::uint32_t>(),
                               mf.tile_size, mf.border);
            const auto& pt = jp.at("page_table");
            const auto x = pt.at("x").get<std::uint32_t>(), y = pt.at("y").get<std::uint32_t>();
            if (pt.at("width").get<std::uint32_t>() != g.page_table_width() ||
                pt.at("height").get<std::uint32_t>() != g.page_table_height() ||
                jp.at("levels").size() != g.levels() ||
                jp.at("first_entry").get<std::uint64_t>() != entries)
                throw IoError(path + ": geometry of painting '" + info.name +
                              "' does not match its size");
            if (x % g.page_table_width() || y % g.page_table_height() ||
                std::uint64_t(x) + g.page_table_width() > mf.table_width ||
                std::uint64_t(y) + g.page_table_height() > mf.table_height)
                throw IoError(path + ": page-table offset of painting '" + info.name +
                              "' is unaligned or outside the merged table");
            g.place(x, y, entries);
            entries += g.total_tiles();
            info.geometry = std::move(g);
            mf.paintings.push_back(std::move(info));
        }
        if (m.at("tile_count").get<std::uint64_t>() != entries)
            throw IoError(path + ": tile_count does not match the paintings");
        mf.tile_count = entries;
        json extra = m.at("page_table");
        extra.erase("width");
        extra.erase("height");
        mf.page_table_extra = extra.dump();
    } catch (const json::exception& e) {
        throw IoError(path + ": malformed manifest: " + e.what());
    } catch (const InvalidArgument& e) {
        throw IoError(path + ": " + e.what());
    }
    if (text_out) *text_out = m.dump();
    return mf;
}

}  // namespace gigascroll
