// Built-in scenes: each fills a Scene (not yet committed) and returns its default camera.
//  - cornell: the geometry, materials, light and camera of Mitsuba 3's mitsuba.cornell_box(),
//    so Mitsuba's path tracer is a reference;
//  - office: a procedurally built office of about 710k triangles (desks, chairs, monitors,
//    keyboards, shelves of books, ceiling panels and a coloured lamp), like VR-photon-mapping's;
//  - furnace: a closed sphere, uniform albedo rho and emission Le everywhere, so the radiance
//    is Le / (1 - rho) in every direction.
#pragma once
#include <string>

#include "views/camera.h"
#include "photon/scene.h"

namespace gigascroll {

Camera build_cornell(Scene& scene, int width = 256, int height = 256);
Camera build_office(Scene& scene, int width = 256, int height = 256);
Camera build_furnace(Scene& scene, float albedo, float emission, int width = 64, int height = 64);
// By name: "cornell", "office" or "furnace" (albedo and emission are the furnace's);
// InvalidArgument for any other name.
Camera build_scene(const std::string& name, Scene& scene, int width, int height, float albedo,
                   float emission);

}  // namespace gigascroll
