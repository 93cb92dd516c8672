#include "bindings/bindings.h"

NB_MODULE(_core, m) {
    m.doc() = "gigascroll C++ core: virtual texturing and photon mapping";
    using namespace gigascroll::bindings;
    bind_common(m);
    bind_pack(m);
    bind_views(m);
    bind_loading(m);
    bind_cache(m);
    bind_sampling(m);
    bind_display(m);
    bind_photon(m);
    bind_gallery(m);
}
