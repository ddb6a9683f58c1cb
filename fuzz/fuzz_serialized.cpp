// The Mitsuba .serialized mesh reader on arbitrary bytes; the first byte picks the shape index.
#include "fuzz_input.h"
#include "mvpt/io/mesh_data.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size == 0) return 0;
    const auto path = mvpt::fuzz::as_file(data + 1, size - 1, ".serialized");
    try {
        mvpt::read_serialized(path, data[0] % 4, {"fuzz.xml", 1, 1});
    } catch (const std::exception &) {
    }
    return 0;
}
