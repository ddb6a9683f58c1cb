// The image readers (OpenEXR, PNG, JPEG, Radiance HDR) on arbitrary bytes; the first byte picks
// the format by the file name's extension.
#include "fuzz_input.h"
#include "mvpt/io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size == 0) return 0;
    static const char *ext[] = {".exr", ".png", ".hdr", ".jpg"};
    const auto path = mvpt::fuzz::as_file(data + 1, size - 1, ext[data[0] % 4]);
    try {
        mvpt::read_image(path);
    } catch (const std::exception &) {
    }
    return 0;
}
