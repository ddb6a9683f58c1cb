// The scene loader on arbitrary XML: substitutions, includes, every plugin's parameters.
// Bad input must end in a SceneError (or another exception), never a crash or a hang.
#include "mvpt/loader/load_scene.h"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const std::string xml(reinterpret_cast<const char *>(data), size);
    try {
        mvpt::load_scene_string(xml, FUZZ_SCENE_DIR);
    } catch (const std::exception &) {
    }
    return 0;
}
