#include "pack/format.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "common/error.h"

namespace gigascroll {

void require_regular_file(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        throw IoError(path + ": cannot open: " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw IoError(path + ": not a regular file");
}

Codec parse_codec(const std::string& name) {
    if (name == "raw") return Codec::Raw;
    if (name == "zstd") return Codec::Zstd;
    if (name == "bc1") return Codec::Bc1;
    throw InvalidArgument("unknown codec '" + name + "' (expected raw, zstd or bc1)");
}

const char* codec_name(Codec codec) {
    switch (codec) {
        case Codec::Zstd: return "zstd";
        case Codec::Bc1: return "bc1";
        default: return "raw";
    }
}

}  // namespace gigascroll
