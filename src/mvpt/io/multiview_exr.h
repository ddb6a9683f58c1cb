// Multi-view OpenEXR: every camera of a render in one multi-part file.
//
// Layout (OpenEXR 2.0+ multi-part, "Storing Multi-View Images in OpenEXR Files"):
// one scan-line part per view, in scene order; the part's name and its `view`
// attribute are the view's name (the view id unless renamed, e.g. to left/right
// for stereo); every header carries a `multiView` attribute listing all view
// names, so the first view is the default view. Each part's data window is its
// own size; the display window (an attribute shared by all parts) is the
// largest width x height among the views.
#pragma once

#include "image_io.h"

#include <filesystem>
#include <string>
#include <vector>

namespace mvpt {

/// One view of a multi-view EXR: its name and its float channels (`width*height` each).
struct ExrView {
    std::string name;
    int width = 0, height = 0;
    std::vector<ExrChannel> channels;
};

/// Write all `views` as parts of one multi-part EXR (atomically); names must be unique and non-empty.
void write_multiview_exr(const std::filesystem::path &path, const std::vector<ExrView> &views);

/// Every part of an EXR (multi-part or not) as float channels; a part's name is its `view`
/// attribute, else its part name, else its index. Data windows are read from their origin.
std::vector<ExrView> read_multiview_exr(const std::filesystem::path &path);

} // namespace mvpt
