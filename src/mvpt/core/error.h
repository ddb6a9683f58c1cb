// Errors that carry a source location (file:line:col) for scene files.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

namespace mvpt {

/// The length of the well-formed UTF-8 sequence at s[i], or 0 if it is not one (overlong forms,
/// surrogates and code points past U+10FFFF are not).
inline size_t utf8_sequence(std::string_view s, size_t i) {
    const auto b = [&](size_t k) { return i + k < s.size() ? (unsigned char)s[i + k] : 0u; };
    const unsigned c = b(0);
    auto cont = [&](size_t k) { return (b(k) & 0xC0u) == 0x80u; };
    if (c < 0x80) return 1;
    if (c >= 0xC2 && c <= 0xDF) return cont(1) ? 2 : 0;
    if (c >= 0xE0 && c <= 0xEF) {
        const unsigned lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
        return b(1) >= lo && b(1) <= hi && cont(2) ? 3 : 0;
    }
    if (c >= 0xF0 && c <= 0xF4) {
        const unsigned lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
        return b(1) >= lo && b(1) <= hi && cont(2) && cont(3) ? 4 : 0;
    }
    return 0;
}

/// The offset of the first byte of `s` that is not well-formed UTF-8, or npos.
inline size_t first_invalid_utf8(std::string_view s) {
    for (size_t i = 0; i < s.size();) {
        const size_t n = utf8_sequence(s, i);
        if (n == 0) return i;
        i += n;
    }
    return std::string_view::npos;
}

/// `s` with every byte that is not well-formed UTF-8 written as \xNN (messages must be text).
inline std::string escape_invalid_utf8(std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (size_t i = 0; i < s.size();) {
        const size_t n = utf8_sequence(s, i);
        if (n > 0) {
            out.append(s.substr(i, n));
            i += n;
        } else {
            char hex[5];
            std::snprintf(hex, sizeof(hex), "\\x%02X", (unsigned char)s[i++]);
            out += hex;
        }
    }
    return out;
}

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
        : std::runtime_error(escape_invalid_utf8(loc.str() + ": " + msg)), m_loc(loc), m_msg(escape_invalid_utf8(msg)) {
        m_loc.file = escape_invalid_utf8(m_loc.file);
    }
    const FileLoc &loc() const { return m_loc; }
    const std::string &message() const { return m_msg; }

private:
    FileLoc m_loc;
    std::string m_msg;
};

} // namespace mvpt
