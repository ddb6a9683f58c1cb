// The scene: shapes in an Embree BVH, lights, cameras (views), integrator; its ray queries.
// Scene files are read into it by the loader (loader/load_scene.h).
#pragma once

#include "../render/integrator.h"
#include "../render/camera.h"
#include "../render/light.h"
#include "../render/shape.h"
#include "segment_cull.h"

#include <embree3/rtcore.h>

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace mvpt {

/// Rays as columns (structure of arrays), all with tmin 0: origins, directions, t_max, times.
struct RayColumns {
    const float *ox, *oy, *oz, *dx, *dy, *dz, *t_max, *time;
};

/// What a scene is made of, as the loader found it in a scene file.
struct SceneParts {
    std::vector<std::shared_ptr<Shape>> shapes;  ///< rendered (shape groups only through instances)
    std::vector<std::shared_ptr<Light>> lights;  ///< besides the shapes' area emitters
    std::vector<std::shared_ptr<Camera>> cameras;
    std::shared_ptr<Integrator> integrator;
    std::vector<std::filesystem::path> source_files;
    std::vector<std::string> notes;
    /// Data the scene lost while it was read (a mesh's degenerate triangles), said once each.
    std::vector<std::string> warnings;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene &) = delete;
    Scene &operator=(const Scene &) = delete;

    /// Takes the parts over and commits the BVH of the shapes.
    void build(SceneParts parts);

    /// Closest hit along `ray` within [tmin, tmax) at `ray.time`.
    bool intersect(const Ray &ray, SurfaceInteraction &si) const;
    /// True if anything blocks `ray` within [tmin, tmax).
    bool occluded(const Ray &ray) const;
    /// Closest hits of `n` rays, traced as 16-wide Embree packets (`coherent`: as one
    /// coherent stream, for a tile's camera rays); `hit[i]` is 0 on a miss. Each result
    /// equals what `intersect` computes from Embree's hit.
    void intersect(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit, bool coherent = false) const;
    /// `occluded` for `n` unrelated rays at once, into `blocked` (16-wide packets).
    void occluded(const Ray *rays, size_t n, uint8_t *blocked) const;
    /// The same for rays given as columns (a wavefront's shadow rays): no repacking of Ray structs.
    void occluded(const RayColumns &rays, size_t n, uint8_t *blocked) const;
    /// Visibility of `n` segments from one origin `o` at scene time `time`: unit directions
    /// (dx, dy, dz) and finite lengths `t_max` as arrays, traced as 8-wide packets; a
    /// segment with t_max <= 0 (or NaN) is not traced (not blocked). The arrays hold n rounded
    /// up to a multiple of 8 entries, the padding with t_max <= 0. Equals `occluded` of each
    /// segment's ray. With prepare_segment_culling, a bundle that provably meets no occluder
    /// is not traced; `across` orients its bounding pyramid (SegmentBundle::build).
    void occluded_segments(Point3f o, const float *dx, const float *dy, const float *dz, const float *t_max, size_t n,
                           float time, uint8_t *blocked, Vec3f across = Vec3f(1.f, 0.f, 0.f)) const;

    /// Build the occluder tree with which `occluded_segments` proves bundles of segments
    /// unblocked without tracing them (static scenes; multi-view rendering calls it once
    /// before its passes). `enable = false` drops it (for tests).
    void prepare_segment_culling(bool enable = true) const;
    /// The occluder tree of prepare_segment_culling, or null.
    const OccluderBvh *occluder_bvh() const { return m_occluders.get(); }
    const std::vector<std::shared_ptr<Shape>> &shapes() const { return m_shapes; }
    const std::vector<std::shared_ptr<Light>> &lights() const { return m_lights; }
    /// The environment light (constant or envmap), if any.
    const Light *environment() const { return m_environment; }
    const std::vector<std::shared_ptr<Camera>> &cameras() const { return m_cameras; }
    const Integrator &integrator() const { return *m_integrator; }
    /// The files the scene was read from (XML, meshes, textures, ...), absolute, without repeats.
    const std::vector<std::filesystem::path> &source_files() const { return m_source_files; }
    /// Notes on how the scene was read (a Mitsuba 0.6 file upgraded, and what that changed).
    const std::vector<std::string> &notes() const { return m_notes; }
    const std::vector<std::string> &warnings() const { return m_warnings; }
    /// How the scene was loaded: the <default> overrides and the rig option.
    const std::map<std::string, std::string> &defines() const { return m_defines; }
    const std::string &rig() const { return m_rig; }
    void set_load_options(std::map<std::string, std::string> defines, std::string rig) {
        m_defines = std::move(defines), m_rig = std::move(rig);
    }
    void set_integrator(std::shared_ptr<Integrator> i) { m_integrator = std::move(i); }
    const BoundingBox &bounds() const { return m_bounds; }
    /// True when a shape bounds a participating medium or a sensor sits in one.
    bool has_media() const { return m_has_media; }
    /// Those media, each once.
    const std::vector<const Medium *> &media() const { return m_media; }
    /// True when some shape moves (animated transforms): then time matters to every ray.
    bool is_animated() const { return m_animated; }
    RTCDevice device() const { return m_device; }
    /// The committed Embree scene (for batched queries and benchmarks).
    RTCScene embree_scene() const { return m_scene; }

private:
    /// `ray` as Embree's record, before the hit; an untraceable ray as an inactive one (tnear > tfar).
    RTCRayHit to_embree(const Ray &ray) const;
    /// Coherent rays (a tile's camera rays) as one stream, in packets of Embree's choice.
    void intersect_stream(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit) const;
    /// Incoherent rays as 16-wide packets.
    void intersect_packets(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit) const;
    /// Completes a hit reported by Embree (geometry ids, primitive, barycentrics).
    void fill_hit(const Ray &ray, float t, unsigned geom, unsigned inst, uint32_t prim, Vec2f b,
                  SurfaceInteraction &si) const;

    RTCDevice m_device = nullptr;
    RTCScene m_scene = nullptr;
    std::vector<std::shared_ptr<Shape>> m_shapes;
    std::vector<const Shape *> m_geom_to_shape;
    std::vector<std::shared_ptr<Light>> m_lights;
    const Light *m_environment = nullptr;
    std::vector<std::shared_ptr<Camera>> m_cameras;
    std::shared_ptr<Integrator> m_integrator;
    BoundingBox m_bounds;
    MotionTime m_motion;
    /// See prepare_segment_culling (built on demand, outside the parallel render loops).
    mutable std::unique_ptr<OccluderBvh> m_occluders;
    mutable std::mutex m_occluders_mutex;
    /// Some shape moves (otherwise Embree's ray time is irrelevant and left at 0).
    bool m_animated = false;
    bool m_has_media = false;
    std::vector<const Medium *> m_media;
    std::vector<std::filesystem::path> m_source_files;
    std::vector<std::string> m_notes, m_warnings;
    std::map<std::string, std::string> m_defines;
    std::string m_rig;
};

} // namespace mvpt
