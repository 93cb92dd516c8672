// The colour record a painting of a manifest may carry (manifest.schema.json's $defs/colour):
// what the stored 8-bit values mean and how they were made. The core checks it with the
// schema's rules so that it refuses exactly what the pure-Python reader (which validates
// against the schema) refuses, and so that no builder writes a record a reader would refuse.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace gigascroll {

// InvalidArgument naming `where` (e.g. "paintings[0].colour") and the field unless `colour`
// follows the schema: an object with mode, source_space, profile (null or an ICC profile's
// description, sha256, bytes, colour_space and class), stored_space and transform, and
// optionally chromaticities (8 numbers), intent and black_point_compensation; other keys
// are allowed (the schema allows them).
void check_colour_record(const nlohmann::json& colour, const std::string& where);

}  // namespace gigascroll
