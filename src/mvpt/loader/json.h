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

struct JsonMember;

/// One JSON value (RFC 8259): null, boolean, number, string, array or object.
struct JsonValue {
    enum class Kind { Null, Bool, Number, String, Array, Object };
    Kind kind = Kind::Null;
    bool boolean = false;
    double number = 0;
    std::string string;
    std::vector<JsonValue> items;                          ///< array elements
    std::vector<JsonMember> members;                       ///< object members, in file order
    FileLoc loc;                                           ///< where the value starts

    /// The member `key` of an object, or nullptr.
    const JsonValue *find(const std::string &key) const;
    /// "null", "a boolean", "a number", "a string", "an array" or "an object" (for messages).
    const char *kind_name() const;
};

/// A member of an object: its key and value (a pair of a type still incomplete in JsonValue
/// would not be portable).
struct JsonMember {
    std::string first;
    JsonValue second;
};

/// Parse JSON text; syntax errors throw SceneError at `display_path`:line:col.
JsonValue parse_json(const std::string &text, const std::string &display_path);
/// Read and parse a JSON file.
JsonValue read_json_file(const std::filesystem::path &path);

} // namespace mvpt
