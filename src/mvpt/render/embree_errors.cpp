#include "embree_errors.h"

#include <stdexcept>
#include <string>

namespace mvpt {

void embree_check(RTCDevice device, const char *what, const void *result) {
    const RTCError code = device ? rtcGetDeviceError(device) : rtcGetDeviceError(nullptr);
    if (code == RTC_ERROR_NONE && result) return;
    if (code == RTC_ERROR_OUT_OF_MEMORY || (code == RTC_ERROR_NONE && !result))
        throw std::runtime_error(std::string("out of memory: Embree could not allocate ") + what +
                                 " (is a memory limit set, by ulimit -v or a container?)");
    throw std::runtime_error(std::string("Embree failed (error ") + std::to_string(int(code)) + ") while building " + what);
}

} // namespace mvpt
