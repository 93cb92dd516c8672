#include "pack/format.h"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "common/checksum.h"
#include "common/error.h"

namespace gigascroll {

std::string tile_file_name(std::uint32_t painting) {
    char name[32];
    std::snprintf(name, sizeof name, "tiles-%05u.bin", painting);
    return name;
}

bool is_plain_file_name(const std::string& name) {
    if (name.empty() || name.size() > 255 || name[0] == '.') return false;
    for (const char c : name)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-'))
            return false;
    return true;
}

std::uint64_t tile_checksum(std::uint32_t version, std::uint64_t packed_key, const void* data,
                            std::size_t size) {
    return version >= 2 ? checksum64(data, size, packed_key ^ kTileSeedSalt) : checksum64(data, size);
}

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
