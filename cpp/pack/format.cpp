#include "pack/format.h"

#include "common/error.h"

namespace gigascroll {

Codec parse_codec(const std::string& name) {
    if (name == "raw") return Codec::Raw;
    if (name == "zstd") return Codec::Zstd;
    throw InvalidArgument("unknown codec '" + name + "' (expected raw or zstd)");
}

const char* codec_name(Codec codec) { return codec == Codec::Zstd ? "zstd" : "raw"; }

}  // namespace gigascroll
