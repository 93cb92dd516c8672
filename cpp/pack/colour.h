// Colour management at ingest: an ICC profile's pixels converted to sRGB with LittleCMS 2,
// 16 bits per channel in and out (float inside), a band at a time (fed by the Python build).
// Thread safety: apply() may be called from several threads at once (no transform cache).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gigascroll {

enum class RenderingIntent : std::uint32_t { Perceptual = 0, Relative = 1, Saturation = 2, Absolute = 3 };

// "perceptual" / "relative" / "saturation" / "absolute"; InvalidArgument otherwise.
RenderingIntent parse_intent(const std::string& name);

class IccTransform {
public:
    // `profile`: the ICC profile's bytes (RGB, grey or CMYK: 3, 1 or 4 channels); the target is
    // LittleCMS' built-in sRGB (IEC 61966-2-1). InvalidArgument when LittleCMS cannot open
    // the profile or build the transform (corrupt, wrong colour space, device link, ...).
    IccTransform(const std::vector<std::uint8_t>& profile, RenderingIntent intent,
                 bool black_point_compensation);
    ~IccTransform();
    IccTransform(const IccTransform&) = delete;
    IccTransform& operator=(const IccTransform&) = delete;

    unsigned channels() const { return channels_; }  // input channels (1 grey, 3 RGB, 4 CMYK)
    // `pixels` pixels of channels() uint16 each -> `pixels` x 3 uint16 sRGB, on `threads`
    // threads (0 = all cores).
    void apply(const std::uint16_t* in, std::size_t pixels, std::uint16_t* out,
               unsigned threads = 0) const;
    // The same for 8-bit input (matrix/TRC RGB profiles: LittleCMS' matrix-shaper path).
    void apply(const std::uint8_t* in, std::size_t pixels, std::uint16_t* out,
               unsigned threads = 0) const;

private:
    void* transform_ = nullptr;   // cmsHTRANSFORM, float in and out
    void* transform8_ = nullptr;  // 8-bit RGB in, 16 out (matrix/TRC profiles only)
    unsigned channels_ = 3;
    float input_scale_ = 1.0f / 65535.0f;  // 16-bit sample -> LittleCMS' float input range
};

// LittleCMS' version, e.g. "2.14".
std::string lcms_version();

}  // namespace gigascroll
