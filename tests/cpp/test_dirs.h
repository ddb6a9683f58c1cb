// A fresh, empty directory for a test's files.
#pragma once

#include <filesystem>
#include <string>

/// temp_directory_path()/name, emptied and created.
inline std::filesystem::path fresh_test_dir(const std::string &name) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}
