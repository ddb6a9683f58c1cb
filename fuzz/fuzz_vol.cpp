// The Mitsuba .vol grid reader (gridvolume) on arbitrary bytes.
#include "fuzz_input.h"
#include "mvpt/io/vol_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const auto path = mvpt::fuzz::as_file(data, size, ".vol");
    try {
        mvpt::read_vol(path, {"fuzz.xml", 1, 1});
    } catch (const std::exception &) {
    }
    return 0;
}
