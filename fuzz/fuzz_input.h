// What the fuzz targets share: the input as a file (the readers take paths), under a name of
// this process so that parallel fuzzers do not meet.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace mvpt::fuzz {

/// Writes `data` to a temporary file ending in `suffix` and returns its path.
inline std::filesystem::path as_file(const uint8_t *data, size_t size, const std::string &suffix) {
    const auto path = std::filesystem::temp_directory_path() / ("mvpt-fuzz-" + std::to_string(getpid()) + suffix);
    std::FILE *f = std::fopen(path.c_str(), "wb");
    if (f) {
        if (size) std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    return path;
}

} // namespace mvpt::fuzz
