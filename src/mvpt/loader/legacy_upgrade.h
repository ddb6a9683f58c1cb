// Scenes written for Mitsuba 0.6 (version < 2.0.0) upgraded on load, element by element.
//
// What Mitsuba 3's loader does: parameter names from camelCase to snake_case (`toWorld`
// -> `to_world`; `<default>` names stay), `<lookAt>` -> `<lookat>`, a `diffuse` BSDF's
// `diffuse_reflectance` -> `reflectance`. Beyond that, the 0.6 features Mitsuba 3 no longer
// has are mapped to their nearest counterpart, each with a note (never silently):
// `roughdiffuse` -> `diffuse`, a bitmap's `trilinear`/`ewa` filter -> `bilinear`, the film's
// LDR settings (`gamma`, `banner`, ...) dropped, a conductor's `ext_eta` of 1 dropped, and
// an integrator Mitsuba 3 lacks (`sppm`, `bdpt`, `mlt`, ...) -> `path` with its depths.
#pragma once

#include "xml_parser.h"

#include <string>
#include <vector>

namespace mvpt {

/// True for a scene version that needs the upgrade (major version below 2).
bool is_legacy_version(int major);

/// Upgrade one element of a 0.6 file whose children are already upgraded; appends a note
/// (once each) for every mapping that changes what is rendered.
void upgrade_legacy_element(XmlNode &node, std::vector<std::string> &notes);

} // namespace mvpt
