// The one wrapper of an Embree device: creation with a configuration string, the error
// callback that records what Embree reports, and check() turning a recorded error into an
// exception at the call that caused it. Scenes of the views and of the photon mapper hold
// one each (the exhibition's is single-threaded, see views/exhibition.cpp).
#pragma once
#include <embree3/rtcore.h>

#include <string>

namespace gigascroll {

class EmbreeDevice {
public:
    // config: Embree's device configuration ("" for its defaults, "threads=1", ...).
    explicit EmbreeDevice(const std::string& config = "");
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDevice handle() const { return device_; }
    // Throws std::runtime_error("Embree: <what>: <error>") if Embree reported an error since
    // the last check (rtcGetDeviceError also clears it).
    void check(const char* what) const;

private:
    RTCDevice device_ = nullptr;
};

}  // namespace gigascroll
