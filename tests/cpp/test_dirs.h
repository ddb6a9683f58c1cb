// A fresh, empty directory for a test's files.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

/// temp_directory_path()/name.<test suite>.<test>, emptied and created: its own for each test,
/// since the tests of one file may run at once (one process each, under ctest -j).
inline std::filesystem::path fresh_test_dir(const std::string &name) {
    const ::testing::TestInfo *test = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::string unique = test ? name + "." + test->test_suite_name() + "." + test->name() : name;
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / unique;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}
