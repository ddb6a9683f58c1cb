// Errors that carry a source location (file:line:col) for scene files.
#pragma once

#include <stdexcept>
#include <string>

namespace mvpt {

/// A position in an input file; line and column are 1-based, 0 when unknown.
struct FileLoc {
    std::string file;
    int line = 0, col = 0;
    std::string str() const {
        if (file.empty()) return "<input>";
        if (line <= 0) return file;
        return file + ":" + std::to_string(line) + ":" + std::to_string(col);
    }
};

/// Bad input: thrown by loaders, reported as "file:line:col: message".
class SceneError : public std::runtime_error {
public:
    SceneError(const FileLoc &loc, const std::string &msg)
        : std::runtime_error(loc.str() + ": " + msg), m_loc(loc), m_msg(msg) {}
    const FileLoc &loc() const { return m_loc; }
    const std::string &message() const { return m_msg; }

private:
    FileLoc m_loc;
    std::string m_msg;
};

} // namespace mvpt
