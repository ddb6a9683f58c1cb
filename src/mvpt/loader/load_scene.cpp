#include "load_scene.h"

#include "../core/plugin.h"
#include "load_control.h"
#include "rig.h"
#include "xml_parser.h"

#include <unordered_set>

namespace mvpt {

SceneParts scene_parts(const SceneTree &tree) {
    const Properties &props = tree.props;
    SceneParts parts;
    parts.source_files = tree.source_files;
    parts.notes = tree.notes;
    parts.warnings = tree.warnings;
    bool environment = false;
    std::unordered_set<std::string> camera_ids; // (a rig makes up to 100000 sensors: no pairwise check)
    for (const ChildObject &c : props.children()) {
        c.queried = true;
        const bool owned_elsewhere = !c.id.empty() && tree.referenced_ids.count(c.id);
        if (c.kind == "shape") {
            if (owned_elsewhere) continue; // e.g. shapes inside a shapegroup reached by <ref>
            auto shape = std::static_pointer_cast<Shape>(c.object);
            if (shape->is_shapegroup()) continue; // rendered only through instances
            parts.shapes.push_back(shape);
        } else if (c.kind == "emitter") {
            auto light = std::static_pointer_cast<Light>(c.object);
            if (light->is_area()) {
                if (!owned_elsewhere)
                    throw SceneError(c.loc, "an 'area' emitter must be placed inside a <shape> (or referenced from one)");
                continue;
            }
            if (owned_elsewhere) continue;
            if (light->is_environment()) {
                if (environment) throw SceneError(c.loc, "the scene has more than one environment emitter");
                environment = true;
            }
            parts.lights.push_back(light);
        } else if (c.kind == "sensor") {
            auto cam = std::static_pointer_cast<Camera>(c.object);
            if (cam->id.empty()) cam->id = std::to_string(parts.cameras.size());
            if (!camera_ids.insert(cam->id).second) throw SceneError(c.loc, "two sensors have the id '" + cam->id + "'");
            parts.cameras.push_back(cam);
        } else if (c.kind == "integrator") {
            if (parts.integrator) throw SceneError(c.loc, "the scene has more than one <integrator>");
            parts.integrator = std::static_pointer_cast<Integrator>(c.object);
        } else if (c.kind == "bsdf" || c.kind == "texture" || c.kind == "medium" || c.kind == "phase" ||
                   c.kind == "volume" || owned_elsewhere) {
            // Declared for <ref> use (materials, textures, or a sampler/film shared by
            // several sensors); unreferenced materials and textures are simply unused.
        } else {
            throw SceneError(c.loc, "a <" + c.kind + "> cannot be placed directly in <scene>");
        }
    }
    props.check_all_queried();
    if (parts.cameras.empty()) throw SceneError(props.loc(), "the scene has no <sensor>: nothing to render");
    if (!parts.integrator) {
        Properties ip("integrator", "path", props.loc());
        parts.integrator = std::static_pointer_cast<Integrator>((*PluginRegistry::find("integrator", "path"))(ip, {}));
    }
    return parts;
}

namespace {
std::unique_ptr<Scene> load(XmlNode root, const std::filesystem::path &base_dir,
                            const std::map<std::string, std::string> &defines, const std::string &rig) {
    if (!rig.empty()) apply_rig_option(root, rig);
    const SceneTree tree = instantiate_scene(root, std::filesystem::absolute(base_dir));
    SceneParts parts = scene_parts(tree);
    check_load_cancelled();
    auto scene = std::make_unique<Scene>();
    scene->build(std::move(parts));
    scene->set_load_options(defines, rig);
    return scene;
}
} // namespace

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path &path, const std::map<std::string, std::string> &defines,
                                       const std::string &rig) {
    return load(parse_scene_file(path, defines), std::filesystem::absolute(path).parent_path(), defines, rig);
}

std::unique_ptr<Scene> load_scene_string(const std::string &xml, const std::filesystem::path &base_dir,
                                         const std::map<std::string, std::string> &defines, const std::string &rig) {
    return load(parse_scene_string(xml, base_dir, defines), base_dir, defines, rig);
}

} // namespace mvpt
