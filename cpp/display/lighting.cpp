#include "display/lighting.h"

namespace gigascroll {

void DisplayLighting::light_batch(const LightQuery* queries, std::size_t count,
                                  SurfaceLight* out) const {
    for (std::size_t i = 0; i < count; ++i) {
        const LightQuery& q = queries[i];
        light(q.geom, q.prim, q.p, q.n, out[i]);
    }
}

}  // namespace gigascroll
