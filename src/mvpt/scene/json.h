// A small JSON reader for side files of scenes (camera-path keyframes): values keep the
// file:line:col where they start, so that errors about their content point at them.
#pragma once

#include "../core/error.h"

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace mvpt {

/// One JSON value (RFC 8259): null, boolean, number, string, array or object.
struct JsonValue {
    enum class Kind { Null, Bool, Number, String, Array, Object };
    Kind kind = Kind::Null;
    bool boolean = false;
    double number = 0;
    std::string string;
    std::vector<JsonValue> items;                          ///< array elements
    std::vector<std::pair<std::string, JsonValue>> members; ///< object members, in file order
    FileLoc loc;                                           ///< where the value starts

    /// The member `key` of an object, or nullptr.
    const JsonValue *find(const std::string &key) const;
    /// "null", "a boolean", "a number", "a string", "an array" or "an object" (for messages).
    const char *kind_name() const;
};

/// Parse JSON text; syntax errors throw SceneError at `display_path`:line:col.
JsonValue parse_json(const std::string &text, const std::string &display_path);
/// Read and parse a JSON file.
JsonValue read_json_file(const std::filesystem::path &path);

} // namespace mvpt
