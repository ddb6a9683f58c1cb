#include "plugin.h"

#include <algorithm>

#include <map>

namespace mvpt {

namespace {
std::map<std::pair<std::string, std::string>, PluginFactory> &registry() {
    static std::map<std::pair<std::string, std::string>, PluginFactory> r;
    return r;
}
} // namespace

bool PluginRegistry::add(const std::string &kind, const std::string &type, PluginFactory f) {
    registry()[{kind, type}] = std::move(f);
    return true;
}

const PluginFactory *PluginRegistry::find(const std::string &kind, const std::string &type) {
    auto it = registry().find({kind, type});
    return it == registry().end() ? nullptr : &it->second;
}

std::vector<std::string> PluginRegistry::types(const std::string &kind) {
    std::vector<std::string> r;
    for (auto &[k, f] : registry())
        if (k.first == kind) r.push_back(k.second);
    return r;
}

namespace {

void add_once(std::vector<std::string> *list, const std::string &text) {
    if (list && std::find(list->begin(), list->end(), text) == list->end()) list->push_back(text);
}

} // namespace

void LoadContext::warn(const std::string &text) const { add_once(warnings, text); }

void LoadContext::note(const std::string &text) const { add_once(notes, text); }

std::filesystem::path LoadContext::resolve(const std::string &name, const FileLoc &loc) const {
    namespace fs = std::filesystem;
    fs::path p(name);
    auto found = [&](fs::path f) {
        if (files) files->push_back(f.lexically_normal());
        return f;
    };
    if (p.is_absolute()) {
        if (fs::is_regular_file(p)) return found(p);
    } else {
        for (auto &dir : search_dirs)
            if (fs::is_regular_file(dir / p)) return found(fs::absolute(dir / p));
    }
    std::string where;
    for (auto &dir : search_dirs) where += (where.empty() ? "" : ", ") + dir.string();
    throw SceneError(loc, "file '" + name + "' not found" + (p.is_absolute() ? "" : " (searched " + where + ")"));
}

} // namespace mvpt
