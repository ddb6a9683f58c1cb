// Mitsuba 3 XML scene files -> a tree of instantiated objects.
//
// Parsing happens in two steps: the XML is read into a tree of `XmlNode`s with
// `<include>` expanded and `$name` variables substituted (`<default>` supplies
// values that the caller's defines override); then objects are instantiated
// depth-first, each from a `Properties` bag that must be read in full.
#pragma once

#include "../core/error.h"
#include "../core/properties.h"

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace mvpt {

/// One attribute of an element (value after `$var` substitution) and where its name starts.
struct XmlAttr {
    std::string first, second; ///< name, value
    FileLoc loc;
    XmlAttr(std::string name, std::string value, FileLoc l = {})
        : first(std::move(name)), second(std::move(value)), loc(std::move(l)) {}
};
using XmlAttrs = std::vector<XmlAttr>;

struct XmlNode {
    std::string tag;
    XmlAttrs attrs;
    std::vector<XmlNode> children;
    FileLoc loc;
    /// Directory of the file the node came from (relative paths resolve there first).
    std::filesystem::path dir;
    /// Root only: directories added by <path value="..."/>, searched after `dir` (latest first, as Mitsuba).
    std::vector<std::filesystem::path> search_dirs;
    /// Root only: the XML files read (the scene's and its includes'), absolute.
    std::vector<std::filesystem::path> source_files;
    /// Root only: notes on how the files were read (Mitsuba 0.6 upgrades).
    std::vector<std::string> notes;

    const std::string *attr(const std::string &name) const {
        for (auto &a : attrs)
            if (a.first == name) return &a.second;
        return nullptr;
    }
    /// Location of attribute `name` (of the element itself when absent or unknown).
    const FileLoc &attr_loc(const std::string &name) const {
        for (auto &a : attrs)
            if (a.first == name && a.loc.line > 0) return a.loc;
        return loc;
    }
};

/// The root `<scene>` node, fully expanded.
XmlNode parse_scene_file(const std::filesystem::path &path, std::map<std::string, std::string> defines);
XmlNode parse_scene_string(const std::string &xml, const std::filesystem::path &base_dir,
                           std::map<std::string, std::string> defines);

/// Instantiated top-level scene: its parameters and children (shapes, emitters, sensors, ...).
struct SceneTree {
    Properties props{"scene", "scene"};
    std::filesystem::path scene_dir;
    /// Ids of top-level objects that other objects reference (and so own).
    std::set<std::string> referenced_ids;
    /// Every file the scene was read from: its XML files, then the files they name, absolute.
    std::vector<std::filesystem::path> source_files;
    /// Notes for the user on how the scene was read (XmlNode::notes).
    std::vector<std::string> notes;
    /// Warnings about the data read (LoadContext::warn).
    std::vector<std::string> warnings;
};

/// Instantiate every object below the root node.
SceneTree instantiate_scene(const XmlNode &root, const std::filesystem::path &scene_dir);

} // namespace mvpt
