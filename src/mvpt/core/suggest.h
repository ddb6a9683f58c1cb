// "Did you mean ...?" hints for misspelt names in scene files.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

namespace mvpt {

/// Edit distance between `a` and `b` counting insertions, deletions, substitutions and swaps
/// of adjacent characters (optimal string alignment distance; case-sensitive).
inline size_t edit_distance(const std::string &a, const std::string &b) {
    std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
    for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (size_t i = 1; i <= a.size(); ++i)
        for (size_t j = 1; j <= b.size(); ++j) {
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[a.size()][b.size()];
}

/// " (did you mean 'x'?)" for the closest candidate within a few edits of `name`, else "".
inline std::string did_you_mean(const std::string &name, const std::vector<std::string> &candidates,
                                const char *quote_open = "'", const char *quote_close = "'") {
    const size_t limit = std::max<size_t>(1, std::min<size_t>(3, name.size() / 3));
    const std::string *best = nullptr;
    size_t best_d = limit + 1;
    for (const std::string &c : candidates) {
        if (c == name) continue;
        size_t d = edit_distance(name, c);
        if (d < best_d) best_d = d, best = &c;
    }
    return best ? std::string(" (did you mean ") + quote_open + *best + quote_close + "?)" : std::string();
}

} // namespace mvpt
