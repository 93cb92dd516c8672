#include "pack/manifest.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "common/bits.h"
#include "common/error.h"
#include "pack/colour_record.h"

namespace gigascroll {

using nlohmann::json;

namespace {

// Manifests larger than this are not packs (a real one is ~1 KB per painting).
constexpr std::uint64_t kMaxManifestBytes = 256ull << 20;
// A manifest nests 4 deep (colour records a little more); deeper is hostile (and recursion
// over it, e.g. when serialising, would exhaust the stack).
constexpr int kMaxJsonDepth = 32;

// JSON text as RFC 8259 defines it and manifest.schema.json reads it: no byte-order mark
// (nlohmann skips one; Python's json refuses it), no NUL byte, no NaN or Infinity, strings of
// valid UTF-8 without lone surrogates, numbers within a double's range (nlohmann refuses
// these three), at most kMaxJsonDepth containers around any value. The pure-Python reader
// (pack/reader.py, parse_manifest_text) applies the same rules.
json parse_bounded(const std::string& text) {
    if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0)
        throw InvalidArgument("a byte-order mark before the JSON text (JSON allows none)");
    // nlohmann reads a NUL as the end of the input (and ignores what follows); valid JSON
    // text holds none (a string escapes it as \u0000).
    if (text.find('\0') != std::string::npos)
        throw InvalidArgument("a NUL byte in the JSON text at byte " +
                              std::to_string(text.find('\0')));
    return json::parse(text, [](int depth, json::parse_event_t, json&) {
        if (depth > kMaxJsonDepth)
            throw InvalidArgument("JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                                  " levels");
        return true;
    });
}

// Text for a message: bytes outside printable ASCII as \xNN, at most `max` bytes of the
// input. Parse errors quote the input's bytes and fields are cut to a length; either may
// split or hold invalid UTF-8, which Python could not turn into a message (it would raise
// UnicodeDecodeError instead of the error).
std::string ascii_escaped(const std::string& text, std::size_t max = std::string::npos) {
    static const char* hex = "0123456789abcdef";
    std::string out;
    for (std::size_t i = 0; i < text.size() && i < max; ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

std::string painting_field(std::size_t i, const char* field) {
    return "paintings[" + std::to_string(i) + "]." + field;
}

// An exact JSON integer in [lo, hi]: floats (even 128.0), booleans, strings and values out of
// range are refused, so nothing is truncated or wrapped on the way in.
std::uint64_t uint_field(const json& obj, const char* key, const std::string& where,
                         std::uint64_t lo, std::uint64_t hi) {
    if (!obj.is_object() || !obj.contains(key))
        throw InvalidArgument("missing field '" + where + "'");
    const json& v = obj.at(key);
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!v.is_number_integer())
        throw InvalidArgument("field '" + where + "' must be an integer in " + range + ", got " +
                              ascii_escaped(v.dump(), 40));
    if (v.is_number_unsigned()) {
        const auto u = v.get<std::uint64_t>();
        if (u >= lo && u <= hi) return u;
    } else if (const auto s = v.get<std::int64_t>(); s >= 0 && std::uint64_t(s) >= lo &&
                                                     std::uint64_t(s) <= hi) {
        return std::uint64_t(s);
    }
    throw InvalidArgument("field '" + where + "' = " + v.dump() + " is outside " + range);
}

std::uint32_t u32_field(const json& obj, const char* key, const std::string& where,
                        std::uint64_t lo, std::uint64_t hi) {
    return static_cast<std::uint32_t>(uint_field(obj, key, where, lo, std::min<std::uint64_t>(hi, UINT32_MAX)));
}

std::string string_field(const json& obj, const char* key, const std::string& where,
                         bool required) {
    if (!obj.contains(key)) {
        if (required) throw InvalidArgument("missing field '" + where + "'");
        return {};
    }
    if (!obj.at(key).is_string()) throw InvalidArgument("field '" + where + "' must be a string");
    return obj.at(key).get<std::string>();
}

const json& object_field(const json& obj, const char* key, const std::string& where) {
    if (!obj.contains(key)) throw InvalidArgument("missing field '" + where + "'");
    if (!obj.at(key).is_object()) throw InvalidArgument("field '" + where + "' must be an object");
    return obj.at(key);
}

const json& array_field(const json& obj, const char* key, const std::string& where) {
    if (!obj.contains(key)) throw InvalidArgument("missing field '" + where + "'");
    if (!obj.at(key).is_array()) throw InvalidArgument("field '" + where + "' must be an array");
    return obj.at(key);
}

// Aligned power-of-two tables are disjoint iff no two intersect; a sweep over x keeps the
// tables crossing the sweep line in a map by y, where they must be disjoint intervals:
// O(n log n) for the 2^16 paintings a pack may hold.
void check_disjoint(const std::vector<PaintingInfo>& ps) {
    struct Event {
        std::uint64_t x;
        bool open;
        std::size_t i;
    };
    std::vector<Event> events;
    events.reserve(2 * ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) {
        const PaintingGeometry& g = ps[i].geometry;
        events.push_back({g.table_x(), true, i});
        events.push_back({std::uint64_t(g.table_x()) + g.page_table_width(), false, i});
    }
    // Closings before openings at the same x: tables that only touch do not overlap.
    std::sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
        return a.x != b.x ? a.x < b.x : (!a.open && b.open);
    });
    std::map<std::uint64_t, std::size_t> active;  // y0 -> painting
    for (const Event& e : events) {
        const PaintingGeometry& g = ps[e.i].geometry;
        const std::uint64_t y0 = g.table_y(), y1 = y0 + g.page_table_height();
        if (!e.open) {
            active.erase(y0);
            continue;
        }
        auto next = active.lower_bound(y0);
        auto clash = [&](std::size_t j) {
            throw InvalidArgument("page tables of paintings[" + std::to_string(j) + "] ('" +
                                  ps[j].name + "') and paintings[" + std::to_string(e.i) +
                                  "] ('" + ps[e.i].name + "') overlap");
        };
        if (next != active.end() && next->first < y1) clash(next->second);
        if (next != active.begin()) {
            const auto prev = std::prev(next);
            const PaintingGeometry& pg = ps[prev->second].geometry;
            if (std::uint64_t(pg.table_y()) + pg.page_table_height() > y0) clash(prev->second);
        }
        active.emplace(y0, e.i);
    }
}

// Painting i is an instance: of an earlier painting that stores its tiles, with its size
// (so its levels, tiles and entries are the source's) and its first entry.
void check_instance(const Manifest& m, std::size_t i) {
    const PaintingInfo& p = m.paintings[i];
    const std::string field = "field '" + painting_field(i, "instance_of") + "'";
    require(m.version >= 2, field + ": a version-1 pack has no instances");
    require(std::uint64_t(p.instance_of) < i,
            field + " = " + std::to_string(p.instance_of) + " must name an earlier painting");
    const PaintingInfo& src = m.paintings[std::size_t(p.instance_of)];
    require(src.instance_of < 0, field + ": paintings[" + std::to_string(p.instance_of) +
                                     "] is itself an instance");
    const PaintingGeometry& g = p.geometry;
    const PaintingGeometry& sg = src.geometry;
    require(g.width() == sg.width() && g.height() == sg.height(),
            "paintings[" + std::to_string(i) + "] ('" + p.name + "'): " +
                std::to_string(g.width()) + " x " + std::to_string(g.height()) +
                " differs from its source's " + std::to_string(sg.width()) + " x " +
                std::to_string(sg.height()));
    require(g.first_entry() == sg.first_entry(),
            "field '" + painting_field(i, "first_entry") + "' = " +
                std::to_string(g.first_entry()) + ", expected its source's " +
                std::to_string(sg.first_entry()));
}

}  // namespace

void validate_manifest(const Manifest& m) {
    require(m.version >= kOldestPackVersion && m.version <= kPackVersion,
            "unsupported pack version " + std::to_string(m.version) + " (this build reads " +
                std::to_string(kOldestPackVersion) + " to " + std::to_string(kPackVersion) + ")");
    check_tile_parameters(m.tile_size, m.border);
    require(!m.paintings.empty(), "field 'paintings': a pack has at least one painting");
    require(m.paintings.size() <= kMaxPackPaintings,
            "field 'paintings': " + std::to_string(m.paintings.size()) +
                " paintings, more than the " + std::to_string(kMaxPackPaintings) +
                " a tile key's 16-bit painting field can address");
    require(is_pow2(m.table_width) && m.table_width <= (1u << 20),
            "field 'page_table.width' = " + std::to_string(m.table_width) +
                " must be a power of two <= 2^20");
    require(is_pow2(m.table_height) && m.table_height <= (1u << 20),
            "field 'page_table.height' = " + std::to_string(m.table_height) +
                " must be a power of two <= 2^20");

    std::uint64_t entries = 0, area = 0, wmax = 0, hmax = 0;
    for (std::size_t i = 0; i < m.paintings.size(); ++i) {
        const PaintingInfo& p = m.paintings[i];
        const PaintingGeometry& g = p.geometry;
        const std::string who = "paintings[" + std::to_string(i) + "] ('" + p.name + "')";
        require(!p.name.empty(), "field '" + painting_field(i, "name") + "' is empty");
        if (!p.colour.empty()) {
            json colour;
            try {
                colour = parse_bounded(p.colour);
            } catch (const json::exception& e) {
                throw InvalidArgument("field '" + painting_field(i, "colour") + "': " + ascii_escaped(e.what()));
            }
            check_colour_record(colour, painting_field(i, "colour"));
        }
        require(g.tile_size() == m.tile_size && g.border() == m.border,
                who + ": tile size or border differs from the pack's");
        require(g.page_table_width() <= (1u << 20) && g.page_table_height() <= (1u << 20),
                who + ": " + std::to_string(g.width()) + " x " + std::to_string(g.height()) +
                    " needs more than 2^20 tiles per axis (the tile key's 20-bit coordinates)");
        require(g.table_x() % g.page_table_width() == 0 && g.table_y() % g.page_table_height() == 0,
                "field '" + painting_field(i, "page_table") + "': offset (" +
                    std::to_string(g.table_x()) + ", " + std::to_string(g.table_y()) +
                    ") is not a multiple of the table's size");
        require(std::uint64_t(g.table_x()) + g.page_table_width() <= m.table_width &&
                    std::uint64_t(g.table_y()) + g.page_table_height() <= m.table_height,
                "field '" + painting_field(i, "page_table") + "': the table lies outside the merged " +
                    std::to_string(m.table_width) + " x " + std::to_string(m.table_height) + " table");
        area += std::uint64_t(g.page_table_width()) * g.page_table_height();
        wmax = std::max<std::uint64_t>(wmax, g.page_table_width());
        hmax = std::max<std::uint64_t>(hmax, g.page_table_height());
        if (p.instance_of >= 0) {
            check_instance(m, i);
            continue;
        }
        require(g.first_entry() == entries,
                "field '" + painting_field(i, "first_entry") + "' = " +
                    std::to_string(g.first_entry()) + ", expected " + std::to_string(entries));
        entries += g.total_tiles();
    }
    require(m.tile_count == entries, "field 'tile_count' = " + std::to_string(m.tile_count) +
                                         ", the paintings have " + std::to_string(entries) + " tiles");
    const std::uint64_t need = std::max(next_pow2(area), wmax * hmax);
    require(std::uint64_t(m.table_width) * m.table_height <= kMaxTableSlack * need,
            "field 'page_table': the merged " + std::to_string(m.table_width) + " x " +
                std::to_string(m.table_height) + " table is absurdly large for paintings whose "
                "tables need " + std::to_string(need) + " entries");
    check_disjoint(m.paintings);

    if (m.version >= 2) {
        require(!m.tile_files.empty() && m.tile_files.size() <= kMaxPackPaintings,
                "field 'tile_files': expected 1 to " + std::to_string(kMaxPackPaintings) + " names");
        std::set<std::string> seen;
        for (std::size_t i = 0; i < m.tile_files.size(); ++i) {
            const std::string& f = m.tile_files[i];
            require(is_plain_file_name(f) && f != kManifestName && f != kIndexName,
                    "field 'tile_files[" + std::to_string(i) + "]' = '" + ascii_escaped(f, 64) +
                        "' is not a plain tile file name");
            require(seen.insert(f).second,
                    "field 'tile_files[" + std::to_string(i) + "]': '" + f + "' is listed twice");
        }
    } else {
        require(m.tile_files.size() == 1 && m.tile_files[0] == kTilesName,
                "a version-1 pack has one tile file, tiles.bin");
    }
}

std::string manifest_text(const Manifest& mf) {
    validate_manifest(mf);
    json extra;
    try {
        extra = parse_bounded(mf.page_table_extra);
    } catch (const json::exception& e) {
        throw InvalidArgument(std::string("page_table_json: ") + ascii_escaped(e.what()));
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
    if (mf.version >= 2) m["tile_files"] = mf.tile_files;
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
        if (p.instance_of >= 0) jp["instance_of"] = p.instance_of;
        if (!p.colour.empty()) {
            json colour;
            try {
                colour = parse_bounded(p.colour);
            } catch (const json::exception& e) {
                throw InvalidArgument("colour of painting '" + p.name + "': " + ascii_escaped(e.what()));
            }
            jp["colour"] = std::move(colour);  // validate_manifest checked it
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

namespace {

// A level holds exactly the schema's six fields (its additionalProperties is false).
void check_level_keys(const json& level, const std::string& where) {
    if (!level.is_object()) throw InvalidArgument("field '" + where + "' must be an object");
    for (const auto& item : level.items()) {
        const std::string& k = item.key();
        if (k != "level" && k != "width" && k != "height" && k != "tiles_x" && k != "tiles_y" &&
            k != "first_entry")
            throw InvalidArgument("field '" + where + "' has an unknown key " +
                                  ascii_escaped(json(k).dump(), 40));
    }
}

Manifest parse_json(const json& m) {
    if (!m.is_object()) throw InvalidArgument("the manifest is not a JSON object");
    Manifest mf;
    if (string_field(m, "format", "format", true) != kManifestFormat)
        throw InvalidArgument("not a gigascroll pack manifest (field 'format')");
    if (m.contains("version") && m.at("version").is_number_integer() &&
        !(m.at("version").is_number_unsigned() &&
          m.at("version").get<std::uint64_t>() >= kOldestPackVersion &&
          m.at("version").get<std::uint64_t>() <= kPackVersion))
        throw InvalidArgument("unsupported pack version " + m.at("version").dump() +
                              " (this build reads " + std::to_string(kOldestPackVersion) + " to " +
                              std::to_string(kPackVersion) + ")");
    mf.version = u32_field(m, "version", "version", kOldestPackVersion, kPackVersion);
    mf.tile_size = u32_field(m, "tile_size", "tile_size", 2, 4096);
    mf.border = u32_field(m, "border", "border", 0, 4096);
    check_tile_parameters(mf.tile_size, mf.border);
    if (uint_field(m, "payload", "payload", 1, 4096) != mf.tile_size - 2 * mf.border)
        throw InvalidArgument("field 'payload' is not tile_size - 2 * border");
    mf.codec = parse_codec(string_field(m, "codec", "codec", true));
    const json& pt = object_field(m, "page_table", "page_table");
    mf.table_width = u32_field(pt, "width", "page_table.width", 1, 1u << 20);
    mf.table_height = u32_field(pt, "height", "page_table.height", 1, 1u << 20);
    if (mf.version >= 2 || m.contains("tiles_bytes"))
        mf.tiles_bytes = uint_field(m, "tiles_bytes", "tiles_bytes", 0, UINT64_MAX);
    if (mf.version >= 2) {
        const json& files = array_field(m, "tile_files", "tile_files");
        if (files.size() > kMaxPackPaintings)
            throw InvalidArgument("field 'tile_files' lists more than " +
                                  std::to_string(kMaxPackPaintings) + " files");
        for (std::size_t i = 0; i < files.size(); ++i) {
            if (!files[i].is_string())
                throw InvalidArgument("field 'tile_files[" + std::to_string(i) + "]' must be a string");
            mf.tile_files.push_back(files[i].get<std::string>());
        }
    } else {
        if (m.contains("tile_files"))
            throw InvalidArgument("field 'tile_files' is not part of a version-1 manifest");
        mf.tile_files = {kTilesName};
    }
    const json& paintings = array_field(m, "paintings", "paintings");
    if (paintings.size() > kMaxPackPaintings)
        throw InvalidArgument("field 'paintings': " + std::to_string(paintings.size()) +
                              " paintings, more than the " + std::to_string(kMaxPackPaintings) +
                              " a tile key's 16-bit painting field can address");
    std::uint64_t entries = 0;
    for (std::size_t i = 0; i < paintings.size(); ++i) {
        const json& jp = paintings[i];
        if (!jp.is_object())
            throw InvalidArgument("field 'paintings[" + std::to_string(i) + "]' must be an object");
        PaintingInfo info;
        info.name = string_field(jp, "name", painting_field(i, "name"), true);
        info.source = string_field(jp, "source", painting_field(i, "source"), false);
        info.conversion = string_field(jp, "conversion", painting_field(i, "conversion"), false);
        if (jp.contains("colour")) {
            check_colour_record(jp.at("colour"), painting_field(i, "colour"));
            info.colour = jp.at("colour").dump();
        }
        PaintingGeometry g(u32_field(jp, "width", painting_field(i, "width"), 1, 1u << 30),
                           u32_field(jp, "height", painting_field(i, "height"), 1, 1u << 30),
                           mf.tile_size, mf.border);
        const std::string ptw = painting_field(i, "page_table");
        const json& ppt = object_field(jp, "page_table", ptw);
        if (u32_field(ppt, "width", ptw + ".width", 1, 1u << 20) != g.page_table_width() ||
            u32_field(ppt, "height", ptw + ".height", 1, 1u << 20) != g.page_table_height())
            throw InvalidArgument("field '" + ptw + "': size does not match the painting's " +
                                  std::to_string(g.width()) + " x " + std::to_string(g.height()));
        const auto x = u32_field(ppt, "x", ptw + ".x", 0, 1u << 20);
        const auto y = u32_field(ppt, "y", ptw + ".y", 0, 1u << 20);
        const auto first = uint_field(jp, "first_entry", painting_field(i, "first_entry"), 0,
                                      UINT64_MAX);
        if (uint_field(jp, "tile_count", painting_field(i, "tile_count"), 0, UINT64_MAX) !=
            g.total_tiles())
            throw InvalidArgument("field '" + painting_field(i, "tile_count") +
                                  "' does not match its levels");
        const json& levels = array_field(jp, "levels", painting_field(i, "levels"));
        if (levels.size() != g.levels())
            throw InvalidArgument("field '" + painting_field(i, "levels") + "' has " +
                                  std::to_string(levels.size()) + " levels, the size gives " +
                                  std::to_string(g.levels()));
        for (std::uint32_t l = 0; l < g.levels(); ++l) {
            const std::string lw = painting_field(i, "levels") + "[" + std::to_string(l) + "]";
            const LevelGeometry& lv = g.level(l);
            const json& jl = levels[l];
            check_level_keys(jl, lw);
            if (uint_field(jl, "level", lw + ".level", 0, 64) != l ||
                uint_field(jl, "width", lw + ".width", 0, UINT64_MAX) != lv.width ||
                uint_field(jl, "height", lw + ".height", 0, UINT64_MAX) != lv.height ||
                uint_field(jl, "tiles_x", lw + ".tiles_x", 0, UINT64_MAX) != lv.tiles_x ||
                uint_field(jl, "tiles_y", lw + ".tiles_y", 0, UINT64_MAX) != lv.tiles_y ||
                uint_field(jl, "first_entry", lw + ".first_entry", 0, UINT64_MAX) != lv.first_tile)
                throw InvalidArgument("field '" + lw + "' does not match the painting's size");
        }
        // uv_scale is derived, but a reader that trusted a different one would sample wrong.
        const std::string uvw = painting_field(i, "uv_scale");
        if (!jp.contains("uv_scale") || !jp.at("uv_scale").is_array() || jp.at("uv_scale").size() != 2 ||
            !jp.at("uv_scale")[0].is_number() || !jp.at("uv_scale")[1].is_number())
            throw InvalidArgument("field '" + uvw + "' must be two numbers");
        const double u = jp.at("uv_scale")[0].get<double>(), v = jp.at("uv_scale")[1].get<double>();
        if (!(u > 0 && u <= 1 && v > 0 && v <= 1))  // the schema's range, before the tolerance
            throw InvalidArgument("field '" + uvw + "' must be two numbers in (0, 1]");
        if (!(std::abs(u - g.uv_scale_u()) <= 1e-9 * g.uv_scale_u()) ||
            !(std::abs(v - g.uv_scale_v()) <= 1e-9 * g.uv_scale_v()))
            throw InvalidArgument("field '" + uvw + "' does not match the painting's size");
        if (jp.contains("instance_of"))  // the rules on it: validate_manifest
            info.instance_of = std::int64_t(
                uint_field(jp, "instance_of", painting_field(i, "instance_of"), 0,
                           kMaxPackPaintings - 1));
        g.place(x, y, first);
        entries += g.total_tiles();
        info.geometry = std::move(g);
        mf.paintings.push_back(std::move(info));
    }
    mf.tile_count = uint_field(m, "tile_count", "tile_count", 0, UINT64_MAX);
    if (pt.contains("packer") &&
        !(pt.at("packer").is_string() &&
          (pt.at("packer").get<std::string>() == "brkga" || pt.at("packer").get<std::string>() == "shelf")))
        throw InvalidArgument("field 'page_table.packer' must be \"brkga\" or \"shelf\"");
    for (const char* ratio : {"fill_ratio", "shelf_fill_ratio", "brkga_fill_ratio"})
        if (pt.contains(ratio) && !(pt.at(ratio).is_number() && pt.at(ratio).get<double>() >= 0 &&
                                    pt.at(ratio).get<double>() <= 1))
            throw InvalidArgument(std::string("field 'page_table.") + ratio + "' must be a number in [0, 1]");
    json extra = pt;
    extra.erase("width");
    extra.erase("height");
    mf.page_table_extra = extra.dump();
    validate_manifest(mf);
    (void)entries;
    return mf;
}

}  // namespace

Manifest parse_manifest(const std::string& text) {
    json m;
    try {
        m = parse_bounded(text);
    } catch (const json::exception& e) {
        throw InvalidArgument(std::string("corrupt manifest: ") + ascii_escaped(e.what()));
    }
    try {
        return parse_json(m);
    } catch (const json::exception& e) {
        throw InvalidArgument(std::string("malformed manifest: ") + ascii_escaped(e.what()));
    }
}

Manifest read_manifest(const std::string& path, std::string* text_out) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        throw IoError(path + ": missing manifest (not a finished tile pack)");
    require_regular_file(path);
    if (std::uint64_t(st.st_size) > kMaxManifestBytes)
        throw IoError(path + ": manifest of " + std::to_string(st.st_size) + " bytes is too large");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": cannot read the manifest");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    Manifest mf;
    json m;
    try {
        m = parse_bounded(buffer.str());
    } catch (const json::exception& e) {
        throw IoError(path + ": corrupt manifest: " + ascii_escaped(e.what()));
    } catch (const InvalidArgument& e) {
        throw IoError(path + ": corrupt manifest: " + ascii_escaped(e.what()));
    }
    try {
        mf = parse_json(m);
    } catch (const json::exception& e) {
        throw IoError(path + ": malformed manifest: " + ascii_escaped(e.what()));
    } catch (const InvalidArgument& e) {
        throw IoError(path + ": " + e.what());
    }
    if (text_out) *text_out = m.dump();
    return mf;
}

}  // namespace gigascroll
