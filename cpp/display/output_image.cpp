#include "display/output_image.h"

#include <string>

#include "common/error.h"

namespace gigascroll {

float* check_output_image(const OutputImage& image, const Camera& eye, const char* what) {
    // Messages appended piecewise (GCC 12 warns falsely on literal + std::string&&).
    auto message = [&](const char* problem) {
        std::string m(what);
        m += problem;
        return m;
    };
    require(image.data != nullptr, message(": no array"));
    require(image.float32, message(": must be float32"));
    require(image.writable, message(": must be writable"));
    if (!(image.ndim == 3 && image.shape[0] == std::int64_t(eye.height) &&
          image.shape[1] == std::int64_t(eye.width) && image.shape[2] == 3)) {
        std::string m = message(": must have shape (");
        m += std::to_string(eye.height);
        m += ", ";
        m += std::to_string(eye.width);
        m += ", 3)";
        throw InvalidArgument(m);
    }
    if (image.strides)
        require(image.strides[2] == 1 && image.strides[1] == 3 &&
                    image.strides[0] == 3 * std::int64_t(eye.width),
                message(": must be C-contiguous"));
    return static_cast<float*>(image.data);
}

void check_disjoint_images(const float* a, const float* b, std::size_t floats) {
    require(a + floats <= b || b + floats <= a, "display: the two eyes' images share memory");
}

}  // namespace gigascroll
