// Which properties of a PLY element form mesh attributes (Mitsuba's naming scheme), and how
// their values become an attribute's channels.
#pragma once

#include <string>
#include <vector>

namespace mvpt {

/// A scalar property of a PLY element that is not geometry: its name and, for integer types,
/// the type's largest value (0 for floating-point types).
struct PlyField {
    std::string name;
    double integer_max = 0.0;
};

/// One mesh attribute read from an element's properties: `fields[c]` (an index into the
/// element's scalar properties) gives channel c, times `scale[c]`.
struct PlyAttributeLayout {
    std::string name;
    std::vector<size_t> fields;
    std::vector<float> scale;
};

/// The attributes of an element whose non-geometry scalar properties are `fields`, named
/// `prefix` ("vertex_" or "face_") + their own name:
/// - r, g, b (or red, green, blue) form `{prefix}color` (3 channels; an alpha is not read);
///   integer colours are divided by their type's largest value, so that 255 is 1;
/// - runs of consecutive properties `{name}_{c}` whose suffixes c follow x y z w, r g b a,
///   0 1 2 3 or 1 2 3 4 from the first form `{prefix}{name}` (with r g b a:
///   `{prefix}{name}_color`) when they are 1 or 3 long;
/// every other property is not an attribute.
std::vector<PlyAttributeLayout> ply_attribute_layout(const std::vector<PlyField> &fields, const std::string &prefix);

} // namespace mvpt
