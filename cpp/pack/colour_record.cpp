#include "pack/colour_record.h"

#include <initializer_list>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace gigascroll {

using nlohmann::json;

namespace {

std::string field(const std::string& where, const char* key) { return where + "." + key; }

// The schema's "enum" of strings: the value must be one of them (a non-string never is).
void require_one_of(const json& v, std::initializer_list<const char*> names,
                    const std::string& where) {
    if (v.is_string())
        for (const char* n : names)
            if (v.get<std::string>() == n) return;
    std::string list;
    for (const char* n : names) list += std::string(list.empty() ? "" : ", ") + n;
    throw InvalidArgument("field '" + where + "' must be one of " + list + ", got " +
                          v.dump(-1, ' ', true).substr(0, 40));  // ASCII: cut anywhere
}

const json& required(const json& obj, const char* key, const std::string& where) {
    if (!obj.contains(key)) throw InvalidArgument("missing field '" + field(where, key) + "'");
    return obj.at(key);
}

void require_string(const json& v, const std::string& where) {
    require(v.is_string(), "field '" + where + "' must be a string");
}

bool is_sha256(const json& v) {
    if (!v.is_string()) return false;
    const std::string& s = v.get_ref<const std::string&>();
    if (s.size() != 64) return false;
    for (const char c : s)
        if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
    return true;
}

// An exact JSON integer (not 128.0, not true) of at least `lo`.
bool is_integer_at_least(const json& v, std::int64_t lo) {
    if (v.is_number_unsigned()) return v.get<std::uint64_t>() >= std::uint64_t(lo);
    return v.is_number_integer() && v.get<std::int64_t>() >= lo;
}

void check_profile(const json& p, const std::string& where) {
    if (p.is_null()) return;
    require(p.is_object(), "field '" + where + "' must be null or an object");
    require_string(required(p, "description", where), field(where, "description"));
    require(is_sha256(required(p, "sha256", where)),
            "field '" + field(where, "sha256") + "' must be 64 lowercase hexadecimal digits");
    require(is_integer_at_least(required(p, "bytes", where), 128),
            "field '" + field(where, "bytes") + "' must be an integer >= 128");
    require_one_of(required(p, "colour_space", where), {"RGB", "GRAY", "CMYK"},
                   field(where, "colour_space"));
    require_one_of(required(p, "class", where), {"mntr", "scnr", "prtr", "spac"},
                   field(where, "class"));
}

}  // namespace

void check_colour_record(const json& colour, const std::string& where) {
    require(colour.is_object(), "field '" + where + "' must be an object");
    require_one_of(required(colour, "mode", where), {"convert", "keep"}, field(where, "mode"));
    require_one_of(required(colour, "source_space", where),
                   {"embedded ICC profile", "EXR chromaticities", "assumed sRGB",
                    "default CMYK profile"},
                   field(where, "source_space"));
    check_profile(required(colour, "profile", where), field(where, "profile"));
    require_one_of(required(colour, "stored_space", where), {"sRGB", "source"},
                   field(where, "stored_space"));
    require_string(required(colour, "transform", where), field(where, "transform"));
    if (colour.contains("chromaticities")) {
        const json& c = colour.at("chromaticities");
        bool ok = c.is_array() && c.size() == 8;
        for (std::size_t i = 0; ok && i < c.size(); ++i) ok = c[i].is_number();
        require(ok, "field '" + field(where, "chromaticities") + "' must be 8 numbers");
    }
    if (colour.contains("intent") && !colour.at("intent").is_null())
        require_one_of(colour.at("intent"), {"perceptual", "relative", "saturation", "absolute"},
                       field(where, "intent"));
    if (colour.contains("black_point_compensation"))
        require(colour.at("black_point_compensation").is_boolean(),
                "field '" + field(where, "black_point_compensation") + "' must be true or false");
}

}  // namespace gigascroll
