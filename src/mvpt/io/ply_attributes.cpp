#include "ply_attributes.h"

#include <algorithm>
#include <set>

namespace mvpt {

namespace {

/// The suffix sequences an attribute's channels may follow (Mitsuba's PLY naming scheme);
/// the second is that of colours.
constexpr const char *Sequences[4] = {"xyzw", "rgba", "0123", "1234"};
constexpr int ColorSequence = 1;

/// Where `name` is `{stem}_{c}` with a one-character suffix c: the stem and c.
bool split_suffix(const std::string &name, std::string &stem, char &c) {
    const size_t at = name.rfind('_');
    if (at == std::string::npos || at == 0 || at + 2 != name.size()) return false;
    stem = name.substr(0, at), c = name.back();
    return true;
}

/// Channel scale of a colour field: integers map their largest value to 1.
float color_scale(const PlyField &f) { return f.integer_max > 0.0 ? float(1.0 / f.integer_max) : 1.f; }

/// r, g, b or red, green, blue as one colour attribute; false when the element has neither.
bool find_plain_color(const std::vector<PlyField> &fields, const std::string &prefix, PlyAttributeLayout &out) {
    for (const auto &names : {std::vector<std::string>{"r", "g", "b"}, std::vector<std::string>{"red", "green", "blue"}}) {
        out.fields.clear();
        for (const std::string &n : names)
            for (size_t i = 0; i < fields.size(); ++i)
                if (fields[i].name == n) out.fields.push_back(i);
        if (out.fields.size() != 3) continue;
        out.name = prefix + "color";
        for (size_t i : out.fields) out.scale.push_back(color_scale(fields[i]));
        return true;
    }
    return false;
}

} // namespace

std::vector<PlyAttributeLayout> ply_attribute_layout(const std::vector<PlyField> &fields, const std::string &prefix) {
    std::vector<PlyAttributeLayout> out;
    PlyAttributeLayout color;
    if (find_plain_color(fields, prefix, color)) out.push_back(color);
    static const std::set<std::string> plain = {"r", "g", "b", "a", "red", "green", "blue", "alpha"};
    std::set<std::string> stems_seen;
    for (size_t i = 0; i < fields.size();) {
        std::string stem;
        char c = 0;
        int seq = -1;
        if (!plain.count(fields[i].name) && split_suffix(fields[i].name, stem, c))
            for (int s = 0; s < 4; ++s)
                if (Sequences[s][0] == c) seq = s;
        if (seq < 0 || stems_seen.count(stem)) { ++i; continue; }
        // The run of properties that continue the sequence with the same stem.
        size_t n = 1;
        std::string next_stem;
        while (n < 4 && i + n < fields.size() && split_suffix(fields[i + n].name, next_stem, c) && next_stem == stem &&
               c == Sequences[seq][n])
            ++n;
        stems_seen.insert(stem);
        const auto taken = [&](const std::string &name) {
            return std::any_of(out.begin(), out.end(), [&](const PlyAttributeLayout &a) { return a.name == name; });
        };
        const std::string name = prefix + stem + (seq == ColorSequence ? "_color" : "");
        if ((n == 1 || n == 3) && !taken(name)) {
            PlyAttributeLayout a;
            a.name = name;
            for (size_t k = 0; k < n; ++k) {
                a.fields.push_back(i + k);
                a.scale.push_back(seq == ColorSequence ? color_scale(fields[i + k]) : 1.f);
            }
            out.push_back(std::move(a));
        }
        i += n;
    }
    return out;
}

} // namespace mvpt
