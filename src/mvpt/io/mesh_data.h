// Triangle mesh data as read from files, before it becomes a shape.
#pragma once

#include "../core/error.h"
#include "../core/math.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mvpt {

/// A named value per vertex or per triangle (Mitsuba's mesh attributes: "vertex_color",
/// "face_weight"), read by mesh_attribute textures.
struct MeshAttribute {
    /// "vertex_..." (interpolated over a triangle) or "face_..." (constant over it).
    std::string name;
    /// Channels per entry: 1 or 3.
    int dim = 1;
    /// dim values per vertex or per triangle.
    std::vector<float> values;

    bool per_face() const { return name.starts_with("face_"); }
};

struct MeshData {
    std::vector<Point3f> positions;
    /// Per-vertex shading normals (empty, or one per position).
    std::vector<Normal3f> normals;
    /// Per-vertex texture coordinates (empty, or one per position).
    std::vector<Vec2f> uvs;
    /// Three vertex indices per triangle.
    std::vector<uint32_t> indices;
    /// Per-vertex and per-triangle attributes (PLY files only).
    std::vector<MeshAttribute> attributes;

    size_t triangle_count() const { return indices.size() / 3; }
};

/// Wavefront OBJ (polygons are fan-triangulated); errors name `loc` and the file.
MeshData read_obj(const std::filesystem::path &path, const FileLoc &loc);
/// Stanford PLY, ASCII or binary (little/big endian).
MeshData read_ply(const std::filesystem::path &path, const FileLoc &loc);
/// Mitsuba's zlib-compressed `.serialized` format; `shape_index` picks the mesh.
MeshData read_serialized(const std::filesystem::path &path, int shape_index, const FileLoc &loc);

} // namespace mvpt
