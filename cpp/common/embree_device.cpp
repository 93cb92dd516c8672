#include "common/embree_device.h"

#include <stdexcept>

namespace gigascroll {
namespace {
const char* error_name(RTCError e) {
    switch (e) {
        case RTC_ERROR_NONE: return "no error";
        case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
        case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
        case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
        case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
        case RTC_ERROR_CANCELLED: return "cancelled";
        default: return "unknown error";
    }
}
// Embree's messages go nowhere: check() reports the error code where it matters.
void ignore_message(void*, RTCError, const char*) {}
}  // namespace

EmbreeDevice::EmbreeDevice(const std::string& config) {
    device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    rtcSetDeviceErrorFunction(device_, ignore_message, nullptr);
}

EmbreeDevice::~EmbreeDevice() {
    if (device_) rtcReleaseDevice(device_);
}

void EmbreeDevice::check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device_);
    if (e != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("Embree: ") + what + ": " + error_name(e));
}

}  // namespace gigascroll
