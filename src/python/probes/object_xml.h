// Single plugins for the probes, built from scene snippets.
#pragma once

#include "mvpt/core/properties.h"

#include <memory>
#include <string>

namespace mvpt_py {

/// The one top-level object of `kind` declared in a scene snippet (paths relative to `base_dir`).
std::shared_ptr<mvpt::Object> object_from_xml(const std::string &xml, const std::string &kind, const std::string &base_dir);

} // namespace mvpt_py
