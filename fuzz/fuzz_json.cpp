// The JSON reader of camera-path key files on arbitrary text.
#include "mvpt/loader/json.h"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    try {
        mvpt::parse_json(std::string(reinterpret_cast<const char *>(data), size), "fuzz.json");
    } catch (const std::exception &) {
    }
    return 0;
}
