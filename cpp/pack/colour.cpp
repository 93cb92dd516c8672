#include "pack/colour.h"

#include <lcms2.h>

#include <algorithm>
#include <memory>
#include <thread>

#include "common/error.h"
#include "common/parallel.h"

namespace gigascroll {
namespace {

// LittleCMS reports errors through a callback: keep the last message per thread.
thread_local std::string lcms_message;

void on_lcms_error(cmsContext, cmsUInt32Number, const char* text) { lcms_message = text ? text : ""; }

struct ProfileCloser {
    void operator()(void* p) const { if (p) cmsCloseProfile(static_cast<cmsHPROFILE>(p)); }
};
using Profile = std::unique_ptr<void, ProfileCloser>;

}  // namespace

RenderingIntent parse_intent(const std::string& name) {
    if (name == "perceptual") return RenderingIntent::Perceptual;
    if (name == "relative") return RenderingIntent::Relative;
    if (name == "saturation") return RenderingIntent::Saturation;
    if (name == "absolute") return RenderingIntent::Absolute;
    throw InvalidArgument("unknown rendering intent '" + name +
                          "' (expected perceptual, relative, saturation or absolute)");
}

IccTransform::IccTransform(const std::vector<std::uint8_t>& profile, RenderingIntent intent,
                           bool black_point_compensation) {
    cmsSetLogErrorHandler(on_lcms_error);
    lcms_message.clear();
    require(!profile.empty(), "empty ICC profile");
    Profile in(cmsOpenProfileFromMem(profile.data(), static_cast<cmsUInt32Number>(profile.size())));
    require(in != nullptr, "LittleCMS cannot open the ICC profile (corrupt?)" +
                               (lcms_message.empty() ? std::string() : ": " + lcms_message));
    const auto h = static_cast<cmsHPROFILE>(in.get());
    const cmsColorSpaceSignature space = cmsGetColorSpace(h);
    const cmsProfileClassSignature cls = cmsGetDeviceClass(h);
    require(cls != cmsSigLinkClass && cls != cmsSigAbstractClass && cls != cmsSigNamedColorClass,
            "the ICC profile is a device link, abstract or named-colour profile");
    require(space == cmsSigRgbData || space == cmsSigGrayData || space == cmsSigCmykData,
            "unsupported ICC colour space (only RGB, grey and CMYK profiles can be converted)");
    channels_ = space == cmsSigRgbData ? 3 : space == cmsSigCmykData ? 4 : 1;
    // LittleCMS' float CMYK is ink percentage (0..100), its float RGB and grey 0..1.
    input_scale_ = (space == cmsSigCmykData ? 100.0f : 1.0f) / 65535.0f;
    Profile srgb(cmsCreate_sRGBProfile());
    // Float in and out: LittleCMS then evaluates the profiles' curves and matrices exactly
    // (a 16-bit transform would be resampled into a CLUT that interpolates across the gamut
    // boundary, several 8-bit steps off where channels clip). Out-of-gamut values are
    // clipped per channel afterwards.
    cmsUInt32Number flags = cmsFLAGS_NOCACHE;
    if (black_point_compensation) flags |= cmsFLAGS_BLACKPOINTCOMPENSATION;
    transform_ = cmsCreateTransform(h, channels_ == 3 ? TYPE_RGB_FLT
                                       : channels_ == 4 ? TYPE_CMYK_FLT : TYPE_GRAY_FLT,
                                    static_cast<cmsHPROFILE>(srgb.get()), TYPE_RGB_FLT,
                                    static_cast<cmsUInt32Number>(intent), flags);
    require(transform_ != nullptr, "LittleCMS cannot build a transform from the ICC profile" +
                                       (lcms_message.empty() ? std::string() : ": " + lcms_message));
    // 8-bit RGB matrix/TRC input: LittleCMS' matrix-shaper optimisation (8-bit input tables,
    // a 1.14 fixed-point matrix, 16-bit output curves) is exact to well under an 8-bit step
    // and an order of magnitude faster than the float pipeline. Other profiles keep float.
    if (channels_ == 3 && cmsIsMatrixShaper(h))
        transform8_ = cmsCreateTransform(h, TYPE_RGB_8, static_cast<cmsHPROFILE>(srgb.get()),
                                         TYPE_RGB_16, static_cast<cmsUInt32Number>(intent), flags);
}

IccTransform::~IccTransform() {
    if (transform_) cmsDeleteTransform(static_cast<cmsHTRANSFORM>(transform_));
    if (transform8_) cmsDeleteTransform(static_cast<cmsHTRANSFORM>(transform8_));
}

namespace {

// Runs fn(begin, end) over [0, pixels) in chunks of `chunk`, split over up to `threads` threads.
template <typename Fn>
void parallel_chunks(std::size_t pixels, unsigned threads, std::size_t chunk, Fn fn) {
    if (threads == 0) threads = default_threads();
    const std::size_t parts = std::min<std::size_t>(threads, (pixels + chunk - 1) / chunk);
    if (parts <= 1) {
        fn(std::size_t(0), pixels);
        return;
    }
    std::vector<std::thread> pool;
    const std::size_t per = (pixels + parts - 1) / parts;
    for (std::size_t t = 0; t < parts; ++t) {
        const std::size_t b = t * per, e = std::min(pixels, b + per);
        if (b < e) pool.emplace_back(fn, b, e);
    }
    for (auto& t : pool) t.join();
}

}  // namespace

void IccTransform::apply(const std::uint8_t* in, std::size_t pixels, std::uint16_t* out,
                         unsigned threads) const {
    if (!transform8_) {  // widened exactly: v * 257 is v / 255 at 16 bits
        std::vector<std::uint16_t> wide(pixels * channels_);
        for (std::size_t k = 0; k < wide.size(); ++k) wide[k] = std::uint16_t(in[k] * 257u);
        apply(wide.data(), pixels, out, threads);
        return;
    }
    const std::size_t chunk = 1 << 16;
    parallel_chunks(pixels, threads, chunk, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; i += chunk)
            cmsDoTransform(static_cast<cmsHTRANSFORM>(transform8_), in + i * 3, out + i * 3,
                           static_cast<cmsUInt32Number>(std::min(chunk, end - i)));
    });
}

void IccTransform::apply(const std::uint16_t* in, std::size_t pixels, std::uint16_t* out,
                         unsigned threads) const {
    const std::size_t chunk = 1 << 14;
    parallel_chunks(pixels, threads, chunk, [&](std::size_t begin, std::size_t end) {
        std::vector<float> src(chunk * channels_), dst(chunk * 3);
        for (std::size_t i = begin; i < end; i += chunk) {
            const std::size_t n = std::min(chunk, end - i);
            const std::uint16_t* p = in + i * channels_;
            for (std::size_t k = 0; k < n * channels_; ++k) src[k] = p[k] * input_scale_;
            cmsDoTransform(static_cast<cmsHTRANSFORM>(transform_), src.data(), dst.data(),
                           static_cast<cmsUInt32Number>(n));
            std::uint16_t* q = out + i * 3;
            for (std::size_t k = 0; k < n * 3; ++k) {
                const float v = std::clamp(dst[k], 0.0f, 1.0f);  // NaN-safe: clamp(NaN) -> NaN
                q[k] = static_cast<std::uint16_t>(v == v ? v * 65535.0f + 0.5f : 0.0f);
            }
        }
    });
}

std::string lcms_version() {
    const int v = cmsGetEncodedCMMversion();  // e.g. 2140
    return std::to_string(v / 1000) + "." + std::to_string((v / 10) % 100);
}

}  // namespace gigascroll
