// The OBJ mesh reader on arbitrary bytes.
#include "fuzz_input.h"
#include "mvpt/io/mesh_data.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const auto path = mvpt::fuzz::as_file(data, size, ".obj");
    try {
        mvpt::read_obj(path, {"fuzz.xml", 1, 1});
    } catch (const std::exception &) {
    }
    return 0;
}
