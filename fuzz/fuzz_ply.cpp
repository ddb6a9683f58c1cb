// The PLY mesh reader on arbitrary bytes.
#include "fuzz_input.h"
#include "mvpt/io/mesh_data.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const auto path = mvpt::fuzz::as_file(data, size, ".ply");
    try {
        mvpt::read_ply(path, {"fuzz.xml", 1, 1});
    } catch (const std::exception &) {
    }
    return 0;
}
