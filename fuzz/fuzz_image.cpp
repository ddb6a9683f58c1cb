// The image readers (OpenEXR, PNG, JPEG, Radiance HDR) on arbitrary bytes; the first byte picks
// the format by the file name's extension.
#include "fuzz_input.h"
#include "mvpt/io/image_io.h"

// Real images may be 16384 x 16384 (mvpt::MaxImagePixels); decoding that many under ASan takes
// longer than libFuzzer's timeout, so headers claiming more than 1024 x 1024 are refused here.
constexpr size_t MaxFuzzPixels = size_t(1) << 20;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size == 0) return 0;
    static const char *ext[] = {".exr", ".png", ".hdr", ".jpg"};
    const auto path = mvpt::fuzz::as_file(data + 1, size - 1, ext[data[0] % 4]);
    try {
        mvpt::read_image(path, false, MaxFuzzPixels);
    } catch (const std::exception &) {
    }
    return 0;
}
