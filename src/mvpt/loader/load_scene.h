// Scene files into scenes: parsed (xml_parser.h), a rig applied (rig.h), instantiated as
// plugins, and their objects sorted into the parts of an Embree scene (accel/scene.h).
#pragma once

#include "../accel/scene.h"

#include <filesystem>
#include <map>
#include <memory>
#include <string>

namespace mvpt {

struct SceneTree;

/// Load a Mitsuba 3 XML scene; `defines` override its <default> values. A non-empty `rig`
/// (e.g. "grid:5x5,spacing=0.05", see loader/rig.h) replaces the sensors by the views it
/// generates from the scene's first sensor.
std::unique_ptr<Scene> load_scene_file(const std::filesystem::path &path,
                                       const std::map<std::string, std::string> &defines = {},
                                       const std::string &rig = {});
std::unique_ptr<Scene> load_scene_string(const std::string &xml, const std::filesystem::path &base_dir,
                                         const std::map<std::string, std::string> &defines = {},
                                         const std::string &rig = {});
/// The objects of an instantiated scene file sorted into a scene's parts, checked: an error
/// names the element's file and line.
SceneParts scene_parts(const SceneTree &tree);

} // namespace mvpt
