// The caller's output images of the display pass, checked before a frame is written.
#pragma once
#include <cstddef>
#include <cstdint>

#include "views/camera.h"

namespace gigascroll {

// A caller's output image for one eye as the binding sees it (any array), checked by
// check_output_image to be height x width x 3 float32, C-contiguous and writable, so that
// frames of a stream can be rendered into the same memory (no fresh pages, no page faults).
struct OutputImage {
    void* data = nullptr;
    std::size_t ndim = 0;
    const std::int64_t* shape = nullptr;
    const std::int64_t* strides = nullptr;  // in elements (nullptr: C-contiguous)
    bool float32 = false;
    bool writable = true;
};
// The checked image's floats; what names the argument in the message (ValueError).
float* check_output_image(const OutputImage& image, const Camera& eye, const char* what);
// Two output images of a stereo pair must not share memory (the right eye reads the left's).
void check_disjoint_images(const float* a, const float* b, std::size_t floats);

}  // namespace gigascroll
