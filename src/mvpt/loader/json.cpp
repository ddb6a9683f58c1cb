#include "json.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace mvpt {

const JsonValue *JsonValue::find(const std::string &key) const {
    for (auto &m : members)
        if (m.first == key) return &m.second;
    return nullptr;
}

const char *JsonValue::kind_name() const {
    switch (kind) {
        case Kind::Null: return "null";
        case Kind::Bool: return "a boolean";
        case Kind::Number: return "a number";
        case Kind::String: return "a string";
        case Kind::Array: return "an array";
        default: return "an object";
    }
}

namespace {

/// Recursive-descent parser over the whole text, tracking line and column.
class JsonParser {
public:
    JsonParser(const std::string &text, std::string path) : m_text(text), m_path(std::move(path)) {}

    JsonValue parse_document() {
        skip_space();
        if (m_pos >= m_text.size()) fail("the file is empty (expected a JSON object or array)");
        JsonValue v = parse_value(0);
        skip_space();
        if (m_pos < m_text.size()) fail("unexpected text after the JSON value");
        return v;
    }

private:
    FileLoc here() const { return {m_path, m_line, int(m_pos - m_line_start) + 1}; }
    [[noreturn]] void fail(const std::string &msg) const { throw SceneError(here(), msg); }

    void advance() {
        if (m_text[m_pos] == '\n') { ++m_line; m_line_start = m_pos + 1; }
        ++m_pos;
    }
    void skip_space() {
        while (m_pos < m_text.size() && std::isspace((unsigned char)m_text[m_pos])) advance();
    }
    bool consume(char c) {
        skip_space();
        if (m_pos < m_text.size() && m_text[m_pos] == c) { advance(); return true; }
        return false;
    }
    void expect(char c, const char *context) {
        if (!consume(c)) {
            skip_space();
            std::string got = m_pos < m_text.size() ? std::string("'") + m_text[m_pos] + "'" : "the end of the file";
            fail(std::string("expected '") + c + "' " + context + ", got " + got);
        }
    }

    JsonValue parse_value(int depth) {
        if (depth > 64) fail("JSON nested more than 64 levels deep");
        skip_space();
        JsonValue v;
        v.loc = here();
        if (m_pos >= m_text.size()) fail("unexpected end of the file (expected a value)");
        char c = m_text[m_pos];
        if (c == '{') {
            v.kind = JsonValue::Kind::Object;
            advance();
            if (consume('}')) return v;
            do {
                skip_space();
                if (m_pos >= m_text.size() || m_text[m_pos] != '"') fail("expected a \"key\" in the object");
                std::string key = parse_string();
                expect(':', "after an object key");
                v.members.push_back({key, parse_value(depth + 1)});
            } while (consume(','));
            expect('}', "or ',' in the object");
        } else if (c == '[') {
            v.kind = JsonValue::Kind::Array;
            advance();
            if (consume(']')) return v;
            do v.items.push_back(parse_value(depth + 1));
            while (consume(','));
            expect(']', "or ',' in the array");
        } else if (c == '"') {
            v.kind = JsonValue::Kind::String;
            v.string = parse_string();
        } else if (c == '-' || std::isdigit((unsigned char)c)) {
            v.kind = JsonValue::Kind::Number;
            v.number = parse_number();
        } else if (literal("true")) {
            v.kind = JsonValue::Kind::Bool;
            v.boolean = true;
        } else if (literal("false")) {
            v.kind = JsonValue::Kind::Bool;
        } else if (literal("null")) {
            v.kind = JsonValue::Kind::Null;
        } else {
            fail(std::string("unexpected character '") + c + "' (expected a JSON value)");
        }
        return v;
    }

    bool literal(const char *word) {
        size_t n = std::char_traits<char>::length(word);
        if (m_text.compare(m_pos, n, word) != 0) return false;
        for (size_t i = 0; i < n; ++i) advance();
        return true;
    }

    double parse_number() {
        size_t start = m_pos;
        auto digits = [&] {
            size_t s = m_pos;
            while (m_pos < m_text.size() && std::isdigit((unsigned char)m_text[m_pos])) advance();
            return m_pos > s;
        };
        if (m_text[m_pos] == '-') advance();
        if (!digits()) fail("malformed number");
        if (m_pos < m_text.size() && m_text[m_pos] == '.') { advance(); if (!digits()) fail("malformed number"); }
        if (m_pos < m_text.size() && (m_text[m_pos] == 'e' || m_text[m_pos] == 'E')) {
            advance();
            if (m_pos < m_text.size() && (m_text[m_pos] == '+' || m_text[m_pos] == '-')) advance();
            if (!digits()) fail("malformed number");
        }
        errno = 0;
        double v = std::strtod(m_text.substr(start, m_pos - start).c_str(), nullptr);
        if (errno == ERANGE || !std::isfinite(v)) fail("number out of range");
        return v;
    }

    std::string parse_string() {
        advance(); // opening quote
        std::string s;
        while (true) {
            if (m_pos >= m_text.size() || m_text[m_pos] == '\n') fail("unterminated string");
            char c = m_text[m_pos];
            if (c == '"') { advance(); return s; }
            if (c == '\\') {
                advance();
                if (m_pos >= m_text.size()) fail("unterminated string");
                char e = m_text[m_pos];
                switch (e) {
                    case '"': case '\\': case '/': s += e; break;
                    case 'n': s += '\n'; break;
                    case 't': s += '\t'; break;
                    case 'r': s += '\r'; break;
                    case 'b': s += '\b'; break;
                    case 'f': s += '\f'; break;
                    case 'u': {
                        if (m_pos + 4 >= m_text.size()) fail("bad \\u escape");
                        unsigned code = unsigned(std::strtoul(m_text.substr(m_pos + 1, 4).c_str(), nullptr, 16));
                        for (int i = 0; i < 4; ++i) advance();
                        // UTF-8 encoding of a BMP code point (surrogate pairs are not combined).
                        if (code < 0x80) s += char(code);
                        else if (code < 0x800) { s += char(0xC0 | (code >> 6)); s += char(0x80 | (code & 0x3F)); }
                        else { s += char(0xE0 | (code >> 12)); s += char(0x80 | ((code >> 6) & 0x3F)); s += char(0x80 | (code & 0x3F)); }
                        break;
                    }
                    default: fail(std::string("bad escape '\\") + e + "' in a string");
                }
                advance();
                continue;
            }
            s += c;
            advance();
        }
    }

    const std::string &m_text;
    std::string m_path;
    size_t m_pos = 0, m_line_start = 0;
    int m_line = 1;
};

} // namespace

JsonValue parse_json(const std::string &text, const std::string &display_path) {
    return JsonParser(text, display_path).parse_document();
}

JsonValue read_json_file(const std::filesystem::path &path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw SceneError({path.string()}, "cannot read the file");
    std::stringstream ss;
    ss << f.rdbuf();
    return parse_json(ss.str(), path.string());
}

} // namespace mvpt
