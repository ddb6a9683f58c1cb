// Registry of scene-file plugins: each plugin file registers its factory under
// (kind, type), e.g. ("bsdf", "diffuse"), with MVPT_REGISTER_PLUGIN.
#pragma once

#include "properties.h"

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mvpt {

/// What factories need besides their parameters: where to find files.
struct LoadContext {
    /// Directories searched for relative file names: the including file's, then the scene's.
    std::vector<std::filesystem::path> search_dirs;
    /// Where resolve() records the files it finds (for a scene's identity), if set.
    std::vector<std::filesystem::path> *files = nullptr;
    /// Where warn() and note() record what the user should know about the data read (a mesh
    /// that lost faces; one with zero-area triangles), if set.
    std::vector<std::string> *warnings = nullptr, *notes = nullptr;
    /// Absolute path of an existing file, or a SceneError at `loc`.
    std::filesystem::path resolve(const std::string &name, const FileLoc &loc) const;
    /// Records `text` once (a repeated text, e.g. from an animated shape's keyframes, is kept once).
    void warn(const std::string &text) const;
    void note(const std::string &text) const;
};

using PluginFactory = std::function<std::shared_ptr<Object>(const Properties &, const LoadContext &)>;

class PluginRegistry {
public:
    static bool add(const std::string &kind, const std::string &type, PluginFactory f);
    static const PluginFactory *find(const std::string &kind, const std::string &type);
    /// Registered types of one kind, sorted (for error messages).
    static std::vector<std::string> types(const std::string &kind);
};

#define MVPT_PLUGIN_CAT2(a, b) a##b
#define MVPT_PLUGIN_CAT(a, b) MVPT_PLUGIN_CAT2(a, b)
/// Register `factory` (callable as (const Properties&, const LoadContext&)).
#define MVPT_REGISTER_PLUGIN(kind, type, factory) \
    static const bool MVPT_PLUGIN_CAT(mvpt_plugin_registered_, __COUNTER__) = ::mvpt::PluginRegistry::add(kind, type, factory)

} // namespace mvpt
