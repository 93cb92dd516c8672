#pragma once
#include <cstdint>

#include "photon/renderer.h"
#include "photon/scene.h"
#include "photon/scenes.h"
#include "views/camera.h"

namespace gigascroll {

// A committed Cornell box of size x size pixels and settings for a small, fast render.
struct SmallCornell {
    explicit SmallCornell(int size, std::uint64_t photons) : cam(build_cornell(scene, size, size)) {
        scene.commit();
        settings.photons = photons;
        settings.gather.radius = 0.1f;
    }
    Scene scene;
    Camera cam;
    RenderSettings settings;
};

}  // namespace gigascroll
