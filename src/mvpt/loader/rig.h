// Camera rigs: many views generated from one base camera (issue 4). One implementation
// serves the scene file's <mvpt:rig> element and the `--rig` / `rig=` option of the CLI and
// Python API; both expand to ordinary <sensor> elements before anything is instantiated,
// so every later stage sees plain sensors.
//
// Rig types and parameters (lengths in scene units, in the base camera's frame: +x left,
// +y up, +z forward; views are ordered left to right, top to bottom):
//   stereo  ipd=0.064 [focus_distance]           ids left, right (left = base + ipd/2 along +x)
//   linear  n, baseline [focus_distance]         ids view000..: n views over `baseline` (first
//                                                to last), centred on the base camera
//   grid    COLSxROWS | cols, rows; spacing      ids r{row}c{col}: a rows x cols grid centred on
//           [focus_distance]                     the base camera, `spacing` apart
//   orbit   n, radius [arc=360]                  ids view000..: the base camera rotated about
//                                                the axis along its up (+y) through the point
//                                                `radius` ahead of it; `arc` < 360 spans
//                                                [-arc/2, arc/2] degrees end to end
//   path    FILE | file; frames [fps=24]          ids frame0000..: a camera path from a key file
//           [shutter=0.5] [interpolation]        (camera_path.h); frame i opens at i/fps and
//                                                stays open shutter/fps (> 1 overlaps frames)
// With `focus_distance` D the translated views of stereo/linear/grid rigs get off-axis
// (sheared) frusta: principal_point_offset += (dx / (2 D tan(fov_x/2)), dy / (2 D tan(fov_y/2)))
// for a view moved by (dx, dy), so the plane at depth D in front of the base camera maps to the
// same pixels in every view (a display's zero-parallax plane). Without it views are parallel.
#pragma once

#include "../core/transform.h"
#include "xml_parser.h"

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace mvpt {

/// A rig request: its type and named parameters, each with where it was written.
struct RigSpec {
    struct Param {
        std::string value;
        FileLoc loc;
    };
    std::string type;
    std::string id_prefix; ///< non-empty: view ids become "<prefix>_<id>"
    std::map<std::string, Param> params;
    FileLoc loc;       ///< the rig element, or "--rig <spec>" for the option
    std::string where; ///< "<mvpt:rig>" for messages about the element ("" for the option)

    /// "where: " or "".
    std::string prefix() const { return where.empty() ? std::string() : where + ": "; }

    /// Parse the option syntax "type:token,name=value,..." (e.g. "grid:5x5,spacing=0.05");
    /// a token without '=' is the grid size or the path's key file.
    static RigSpec parse(const std::string &text);
};

/// What a rig needs of its base camera.
struct RigBase {
    Transform to_world;             ///< camera-to-world (static)
    float tan_x = 1.f, tan_y = 1.f; ///< tangents of the half fields of view
    float ppo_x = 0.f, ppo_y = 0.f; ///< the base's own principal point offset
    double pixels = 0.0;            ///< pixels of a view (the film's crop window)
};

/// One generated view.
struct RigView {
    std::string id;
    Transform to_world;                              ///< the pose (at the shutter opening for a path)
    std::vector<std::pair<float, Transform>> motion; ///< path rigs: poses over the shutter (>= 2 keys)
    float ppo_x = 0.f, ppo_y = 0.f;                  ///< principal point offset of the view
    bool has_shutter = false;                        ///< path rigs set the shutter interval
    float shutter_open = 0.f, shutter_close = 0.f;
};

/// Expand `spec` around `base`; relative key files are looked up in `search_dirs` in order,
/// and the file read is appended to `files` (a scene's identity). Bad parameters throw
/// SceneError at the parameter (zero views, NaN spacing, unknown type, ...).
std::vector<RigView> generate_rig(const RigSpec &spec, const RigBase &base,
                                  const std::vector<std::filesystem::path> &search_dirs,
                                  std::vector<std::filesystem::path> *files = nullptr);

/// The sensors of a <mvpt:rig> element (its one child <sensor> is the base camera); `scene`
/// holds the top-level elements read so far (a <ref>'d film is looked up there). A key file
/// it reads is appended to `files`.
std::vector<XmlNode> expand_rig_element(const XmlNode &rig, const XmlNode &scene,
                                        const std::vector<std::filesystem::path> &search_dirs,
                                        std::vector<std::filesystem::path> *files = nullptr);

/// The `--rig` option: replace the scene's top-level sensors by the rig generated from the
/// first one. Relative key files resolve against the working directory, then the scene's; the
/// file read joins the root's source_files.
void apply_rig_option(XmlNode &root, const std::string &spec);

/// True for the element names that denote a rig (the prefix `mvpt:`; see rig_xml.cpp).
bool is_rig_element(const std::string &tag);

} // namespace mvpt
