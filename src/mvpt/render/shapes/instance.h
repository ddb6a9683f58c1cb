// Shape groups and their instances (Mitsuba's `shapegroup` / `instance`), as
// Embree instances of a sub-scene; also the carrier of animated shapes, whose
// `to_world` becomes a motion-blurred instance transform.
#pragma once

#include "../../core/animation.h"
#include "../../core/plugin.h"
#include "../shape.h"

#include <functional>
#include <mutex>
#include <vector>

namespace mvpt {

/// Shapes in their own Embree scene, rendered only through `Instance`s.
class ShapeGroup final : public Shape {
public:
    explicit ShapeGroup(std::vector<std::shared_ptr<Shape>> shapes);
    ~ShapeGroup() override;

    /// The committed sub-scene (built on first use with `device`).
    RTCScene embree_scene(RTCDevice device);
    /// The member with Embree geometry id `geom` in the sub-scene.
    const Shape *member(unsigned geom) const { return geom < m_by_geom.size() ? m_by_geom[geom] : nullptr; }
    const std::vector<std::shared_ptr<Shape>> &shapes() const { return m_shapes; }

    bool is_shapegroup() const override { return true; }
    unsigned attach(RTCDevice, RTCScene, const MotionTime &) override;
    void fill_interaction(const Ray &, float, uint32_t, Vec2f, SurfaceInteraction &) const override;
    float area() const override { return 0.f; }
    BoundingBox bounds() const override { return m_bounds; }
    ShapeSample sample_area(Vec2f) const override { return {}; }

private:
    std::vector<std::shared_ptr<Shape>> m_shapes;
    std::vector<const Shape *> m_by_geom;
    BoundingBox m_bounds;
    RTCScene m_scene = nullptr;
    std::mutex m_build_mutex;
};

/// A shape group placed with a (possibly animated) object-to-world transform.
class Instance final : public Shape {
public:
    Instance(std::shared_ptr<ShapeGroup> group, AnimatedTransform to_world);
    ~Instance() override;

    unsigned attach(RTCDevice device, RTCScene scene, const MotionTime &motion) override;
    void fill_interaction(const Ray &, float, uint32_t, Vec2f, SurfaceInteraction &) const override;
    void fill_instance_interaction(const Ray &ray, float t, unsigned inner_geom, uint32_t prim, Vec2f b,
                                   SurfaceInteraction &si) const override;
    bool time_range(float &begin, float &end) const override;
    float area() const override { return 0.f; }
    BoundingBox bounds() const override;
    ShapeSample sample_area(Vec2f) const override { return {}; }

    /// Object-to-world transform at scene time `time` (as Embree interpolates it).
    Transform transform_at(float time) const;

private:
    std::shared_ptr<ShapeGroup> m_group;
    AnimatedTransform m_to_world;
    RTCGeometry m_geom = nullptr;
    MotionTime m_motion;
};

/// For shape plugins: `make(to_world)` builds the shape. A static `to_world` is
/// passed through; an `<animation>` builds the shape in object space and wraps
/// it in a motion-blurred Instance (an area emitter on it is an error).
std::shared_ptr<Object> make_maybe_animated(const Properties &props,
                                            const std::function<std::shared_ptr<Shape>(const Transform &)> &make);

} // namespace mvpt
