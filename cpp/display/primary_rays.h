// The display pass's primary rays: 16-ray Embree packets along each row of an eye (cast_rows,
// the "trace" step of display/eye_pass.h), and the bare cast that is the pass's baseline cost.
#pragma once
#include <embree3/rtcore.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "common/lanes.h"
#include "views/camera.h"

namespace gigascroll {

// The baseline of the display's cost: the same primary rays (16-ray packets along rows, as
// the pass casts them) with nothing done at the hits. Returns the seconds taken; *hits gets
// the number of rays that hit.
double cast_primary_rays(RTCScene scene, const Camera& eye, unsigned threads = 0,
                         std::uint64_t* hits = nullptr);

namespace display {

constexpr unsigned kNoHit = RTC_INVALID_GEOMETRY_ID;

// InvalidArgument unless the eye's resolution is positive and below 2^31 pixels.
void check_camera(const Camera& eye);
// Rows per parallel chunk of one eye's pass alone (see primary_rays.cpp).
std::size_t rows_per_chunk(std::size_t height, unsigned threads);

// Casts the primary rays of rows [row_begin, row_end) in 16-ray packets along each row; a
// pixel with reused[i] >= 0 (the right eye's pixels that reuse a left hit) is left out of its
// packet, and a packet left empty is not cast. A row's last packet holds n < 16 pixels when
// the width is not a multiple of 16; with whole_tail (and no reused pixels) its other lanes
// cast its last pixel's ray again, so that the packet can be taken whole. on_row_start(row)
// runs before each row's packets, on_packet(row, i0, n, valid, packet) sees each packet after
// Embree filled it, on_row(row) each row after its last packet.
template <typename OnRowStart, typename OnPacket, typename OnRow>
void cast_rows(RTCScene scene, const Camera& eye, std::size_t row_begin, std::size_t row_end,
               const std::int32_t* reused, bool whole_tail, OnRowStart&& on_row_start,
               OnPacket&& on_packet, OnRow&& on_row) {
    const std::uint32_t w = eye.width;
    const std::size_t padded = (std::size_t(w) + 15) / 16 * 16;
    std::vector<float> dir_x(padded), dir_y(padded), dir_z(padded);
    std::vector<double> column_sx(padded);
    for (std::uint32_t i = 0; i < w; ++i) column_sx[i] = eye.screen_x(i + 0.5);
    std::fill(column_sx.begin() + w, column_sx.end(), column_sx[w - 1]);
    RTCRayHit16 packet;
    for (std::uint32_t k = 0; k < 16; ++k) {
        packet.ray.org_x[k] = float(eye.position.x), packet.ray.org_y[k] = float(eye.position.y);
        packet.ray.org_z[k] = float(eye.position.z);
        packet.ray.tnear[k] = 0.f, packet.ray.time[k] = 0.f, packet.ray.mask[k] = ~0u;
        packet.ray.id[k] = k, packet.ray.flags[k] = 0;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    // The ray directions of columns [begin, end) of a row (one loop the compiler vectorises).
    auto directions = [&](const Vec3d& row_dir, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double c = column_sx[i];
            dir_x[i] = float(row_dir.x + c * eye.right.x);
            dir_y[i] = float(row_dir.y + c * eye.right.y);
            dir_z[i] = float(row_dir.z + c * eye.right.z);
        }
    };
    for (std::size_t row = row_begin; row < row_end; ++row) {
        on_row_start(row);
        const Vec3d row_dir = eye.forward + eye.screen_y(row + 0.5) * eye.up;
        const std::int32_t* row_reused = reused ? reused + row * w : nullptr;
        if (!row_reused) directions(row_dir, 0, padded);
        for (std::uint32_t i0 = 0; i0 < w; i0 += 16) {
            const std::uint32_t n = std::min<std::uint32_t>(16, w - i0);
            alignas(64) int valid[16];
            if (row_reused) {
                int any = 0;
                for (std::uint32_t k = 0; k < 16; ++k) {
                    valid[k] = k < n && row_reused[i0 + std::min(k, n - 1)] < 0 ? -1 : 0;
                    any |= valid[k];
                }
                if (!any) continue;
                directions(row_dir, i0, i0 + 16);  // only for the packets that are cast
            } else {  // the lanes below n, all 16 with whole_tail
                // In lanes: one store at 16 (GCC kept a loop over k scalar: 52 instructions a
                // packet).
                using L = Lanes<kWidest>;
                const unsigned lanes = n == 16 || whole_tail ? 0xFFFFu : (1u << n) - 1;
                for (int k = 0; k < 16; k += kWidest)
                    L::select(mask_of<kWidest>(lanes >> k), L::I(-1), L::I(0)).store(valid + k);
            }
            for (std::uint32_t k = 0; k < 16; ++k) {
                packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
                packet.hit.geomID[k] = kNoHit;
            }
            std::memcpy(packet.ray.dir_x, dir_x.data() + i0, sizeof packet.ray.dir_x);
            std::memcpy(packet.ray.dir_y, dir_y.data() + i0, sizeof packet.ray.dir_y);
            std::memcpy(packet.ray.dir_z, dir_z.data() + i0, sizeof packet.ray.dir_z);
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect16(valid, scene, &context, &packet);
            on_packet(row, i0, n, valid, packet);
        }
        on_row(row);
    }
}

}  // namespace display
}  // namespace gigascroll
