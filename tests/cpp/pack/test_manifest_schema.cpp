// The core's manifest rules against manifest.schema.json's: a byte-order mark, an unknown
// key in a level and every field of a colour record are refused as the schema (and the
// pure-Python reader) refuses them, on reading and on writing; messages stay ASCII where the
// input is not valid UTF-8. The Python mutation tests check the two readers agree.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"
#include "pack/colour_record.h"
#include "pack/manifest.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"

using namespace gigascroll;
using nlohmann::json;

namespace {

// A record as the Python build writes it for an image with an embedded ICC profile.
json profile_record() {
    return json::parse(R"({"mode": "convert", "source_space": "embedded ICC profile",
        "profile": {"description": "Display P3", "sha256": ")" + std::string(64, 'a') +
                       R"(", "bytes": 536, "colour_space": "RGB", "class": "mntr"},
        "intent": "relative", "black_point_compensation": true, "stored_space": "sRGB",
        "transform": "LittleCMS 2.14, 16-bit"})");
}

struct OnePainting {
    TempDir dir;
    explicit OnePainting(std::uint32_t side = 20) {
        const auto img = random_image(side, side, 4);
        build(dir.path, img, side, side, 16, 2, Codec::Raw, side, 1);
    }
    json manifest() const {
        std::ifstream in(dir.path / kManifestName);
        return json::parse(in);
    }
};

std::string refusal(const std::string& text) {
    try {
        (void)parse_manifest(text);
    } catch (const InvalidArgument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(ManifestSchema, AByteOrderMarkIsRefusedOnParseAndRead) {
    OnePainting p;
    const std::string text = p.manifest().dump();
    ASSERT_EQ(refusal(text), "");
    EXPECT_NE(refusal("\xEF\xBB\xBF" + text).find("byte-order mark"), std::string::npos);
    std::ofstream(p.dir.path / kManifestName, std::ios::binary) << "\xEF\xBB\xBF" << text;
    EXPECT_THROW(TilePack(p.dir.path.string()), IoError);
}

TEST(ManifestSchema, ALevelHoldsOnlyItsSixFields) {
    OnePainting p;
    json m = p.manifest();
    m["paintings"][0]["levels"][0]["comment"] = "x";
    EXPECT_NE(refusal(m.dump()).find("paintings[0].levels[0]' has an unknown key \"comment\""),
              std::string::npos)
        << refusal(m.dump());
    m = p.manifest();  // other objects may carry more (the schema allows it)
    m["paintings"][0]["comment"] = "x";
    m["page_table"]["comment"] = "x";
    m["comment"] = "x";
    EXPECT_EQ(refusal(m.dump()), "");
}

TEST(ManifestSchema, ColourRecordsFollowTheSchema) {
    EXPECT_NO_THROW(check_colour_record(profile_record(), "c"));
    json none = profile_record();
    none["profile"] = nullptr;
    none["intent"] = nullptr;
    none.erase("black_point_compensation");
    none["chromaticities"] = {0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329};
    none["extra"] = {1, 2};
    EXPECT_NO_THROW(check_colour_record(none, "c"));
    struct Case {
        void (*mutate)(json&);
        const char* field;
    };
    const Case cases[] = {
        {[](json& c) { c.erase("mode"); }, "'c.mode'"},
        {[](json& c) { c["mode"] = "maybe"; }, "'c.mode'"},
        {[](json& c) { c["source_space"] = 3; }, "'c.source_space'"},
        {[](json& c) { c.erase("profile"); }, "'c.profile'"},
        {[](json& c) { c["profile"] = "sRGB"; }, "'c.profile'"},
        {[](json& c) { c["profile"].erase("description"); }, "'c.profile.description'"},
        {[](json& c) { c["profile"]["sha256"] = std::string(63, 'a'); }, "'c.profile.sha256'"},
        {[](json& c) { c["profile"]["sha256"] = std::string(64, 'A'); }, "'c.profile.sha256'"},
        {[](json& c) { c["profile"]["sha256"] = std::string(64, 'a') + "\n"; }, "'c.profile.sha256'"},
        {[](json& c) { c["profile"]["bytes"] = 127; }, "'c.profile.bytes'"},
        {[](json& c) { c["profile"]["bytes"] = 536.0; }, "'c.profile.bytes'"},
        {[](json& c) { c["profile"]["bytes"] = -1; }, "'c.profile.bytes'"},
        {[](json& c) { c["profile"]["colour_space"] = "LAB"; }, "'c.profile.colour_space'"},
        {[](json& c) { c["profile"]["class"] = "link"; }, "'c.profile.class'"},
        {[](json& c) { c["chromaticities"] = {1, 2, 3}; }, "'c.chromaticities'"},
        {[](json& c) { c["chromaticities"] = {1, 2, 3, 4, 5, 6, 7, "8"}; }, "'c.chromaticities'"},
        {[](json& c) { c["intent"] = "colorimetric"; }, "'c.intent'"},
        {[](json& c) { c["black_point_compensation"] = 1; }, "'c.black_point_compensation'"},
        {[](json& c) { c["stored_space"] = "linear"; }, "'c.stored_space'"},
        {[](json& c) { c["transform"] = nullptr; }, "'c.transform'"},
    };
    for (const Case& c : cases) {
        json record = profile_record();
        c.mutate(record);
        try {
            check_colour_record(record, "c");
            ADD_FAILURE() << "accepted " << record.dump();
        } catch (const InvalidArgument& e) {
            EXPECT_NE(std::string(e.what()).find(c.field), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(check_colour_record(json::array(), "c"), InvalidArgument);
}

TEST(ManifestSchema, ABadColourRecordIsNeitherReadNorWritten) {
    OnePainting p;
    json m = p.manifest();
    m["paintings"][0]["colour"] = profile_record();
    EXPECT_EQ(refusal(m.dump()), "");
    m["paintings"][0]["colour"]["mode"] = "maybe";
    EXPECT_NE(refusal(m.dump()).find("paintings[0].colour.mode"), std::string::npos);
    // The builder validates before it writes: no pack with a record the readers refuse.
    TempDir out;
    PackOptions o;
    o.tile_size = 16;
    o.border = 2;
    PackBuilder b(out.path.string(), o);
    const auto img = random_image(20, 20, 5);
    PaintingSpec spec{"img", "test", "none", 20, 20, 0, 0};
    spec.colour = R"({"mode": "maybe"})";
    b.begin_painting(spec);
    b.add_rows(img.data(), 20, 20);
    b.end_painting();
    EXPECT_THROW(b.finish(2, 2), InvalidArgument);
    EXPECT_FALSE(std::filesystem::exists(out.path / kManifestName));
}

TEST(ManifestSchema, UvScaleAboveOneIsRefusedEvenWithinTheTolerance) {
    OnePainting p(24);  // two 12-texel payloads: the table is used in full, uv_scale = 1
    json m = p.manifest();
    ASSERT_EQ(m["paintings"][0]["uv_scale"][0].get<double>(), 1.0);
    m["paintings"][0]["uv_scale"][0] = 1 + 1e-10;  // within the 1e-9 tolerance, above the range
    EXPECT_NE(refusal(m.dump()).find("uv_scale"), std::string::npos);
}

TEST(ManifestSchema, MessagesStayAsciiOnInvalidUtf8) {
    OnePainting p;
    std::string text = p.manifest().dump();
    text.insert(text.find("\"name\":\"") + 8, "\xC3");  // a lead byte without its follower
    const std::string why = refusal(text);
    ASSERT_NE(why, "");
    for (const char c : why) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << why;
    json m = p.manifest();
    std::string accents;
    for (int i = 0; i < 30; ++i) accents += "\xC3\xA9";  // valid UTF-8, cut mid-character
    m["tile_size"] = accents;
    const std::string cut = refusal(m.dump());
    ASSERT_NE(cut.find("tile_size"), std::string::npos) << cut;
    for (const char c : cut) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << cut;
}
