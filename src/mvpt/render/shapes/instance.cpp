#include "instance.h"

#include "../embree_errors.h"
#include "../light.h"

#include <embree3/rtcore_quaternion.h>

#include <cmath>

namespace mvpt {

// ---------------------------------------------------------------- ShapeGroup

ShapeGroup::ShapeGroup(std::vector<std::shared_ptr<Shape>> shapes) : m_shapes(std::move(shapes)) {
    for (auto &s : m_shapes) m_bounds.expand(s->bounds());
}

ShapeGroup::~ShapeGroup() {
    if (m_scene) rtcReleaseScene(m_scene);
}

RTCScene ShapeGroup::embree_scene(RTCDevice device) {
    std::lock_guard<std::mutex> lock(m_build_mutex);
    if (m_scene) return m_scene;
    m_scene = embree_checked(rtcNewScene(device), device, "an instanced group");
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
    for (auto &s : m_shapes) {
        unsigned gid = s->attach(device, m_scene, MotionTime{}); // members never move on their own
        if (gid >= m_by_geom.size()) m_by_geom.resize(gid + 1, nullptr);
        m_by_geom[gid] = s.get();
    }
    rtcCommitScene(m_scene);
    embree_check(device, "an instanced group's bounding volume hierarchy");
    return m_scene;
}

unsigned ShapeGroup::attach(RTCDevice, RTCScene, const MotionTime &) {
    throw std::logic_error("a shapegroup is attached only through instances");
}

void ShapeGroup::fill_interaction(const Ray &, float, uint32_t, Vec2f, SurfaceInteraction &) const {
    throw std::logic_error("a shapegroup is intersected only through instances");
}

// ---------------------------------------------------------------- Instance

namespace {

/// Evenly spaced keyframes (Embree's motion model) covering the scene's
/// Embree time [0, 1] entirely, so that end poses hold outside the animation.
struct MotionSteps {
    std::vector<TransformKey> keys;
    float embree_begin = 0.f, embree_end = 1.f;
};

MotionSteps motion_steps(const AnimatedTransform &at, const MotionTime &motion) {
    const auto &keys = at.keys();
    const double a = keys.front().time, b = keys.back().time, span = double(motion.t1) - motion.t0;
    const size_t n = keys.size();
    const double h = (b - a) / double(n - 1);
    bool even = true;
    for (size_t i = 0; i < n; ++i)
        if (std::abs(keys[i].time - (a + double(i) * h)) > 1e-4 * (b - a)) even = false;
    const double pre = std::max(0.0, std::ceil((a - motion.t0) / h - 1e-6)),
                 post = std::max(0.0, std::ceil((motion.t1 - b) / h - 1e-6));
    MotionSteps ms;
    if (even && pre + post + double(n) <= 1024.0) {
        // The keyframes themselves, padded with copies of the end poses.
        ms.keys.insert(ms.keys.end(), size_t(pre), keys.front());
        ms.keys.insert(ms.keys.end(), keys.begin(), keys.end());
        ms.keys.insert(ms.keys.end(), size_t(post), keys.back());
        ms.embree_begin = float((a - pre * h - motion.t0) / span);
        ms.embree_end = float((b + post * h - motion.t0) / span);
    } else {
        // Uneven keyframes: resample the animation on a fine even grid
        // (exact at the grid points, slerp in between).
        const int steps = 257;
        std::vector<std::pair<float, Transform>> samples;
        for (int i = 0; i < steps; ++i) {
            float t = float(motion.t0 + span * double(i) / (steps - 1));
            samples.emplace_back(t, at.eval(t));
        }
        AnimatedTransform resampled;
        std::string err;
        if (!AnimatedTransform::from_keys(samples, resampled, err)) throw std::runtime_error(err);
        ms.keys = resampled.keys();
    }
    // Consecutive quaternions on the same hemisphere, so that Embree's slerp takes the short arc.
    for (size_t i = 1; i < ms.keys.size(); ++i) {
        Quaternion &q = ms.keys[i].rotation, &p = ms.keys[i - 1].rotation;
        if (p.w * q.w + p.x * q.x + p.y * q.y + p.z * q.z < 0) q = {-q.w, -q.x, -q.y, -q.z};
    }
    return ms;
}

void to_float3x4(const Matrix4 &m, float out[12]) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) out[3 * c + r] = float(m.m[r][c]);
}

} // namespace

Instance::Instance(std::shared_ptr<ShapeGroup> group, AnimatedTransform to_world)
    : m_group(std::move(group)), m_to_world(std::move(to_world)) {}

Instance::~Instance() {
    if (m_geom) rtcReleaseGeometry(m_geom);
}

bool Instance::time_range(float &begin, float &end) const {
    if (!m_to_world.is_animated()) return false;
    begin = m_to_world.t_begin();
    end = m_to_world.t_end();
    return true;
}

unsigned Instance::attach(RTCDevice device, RTCScene scene, const MotionTime &motion) {
    m_motion = motion;
    RTCScene sub = m_group->embree_scene(device);
    m_geom = embree_checked(rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE), device, "an instance");
    rtcSetGeometryInstancedScene(m_geom, sub);
    if (!m_to_world.is_animated()) {
        float xfm[12];
        to_float3x4(m_to_world.eval(0.f).matrix(), xfm);
        rtcSetGeometryTimeStepCount(m_geom, 1);
        rtcSetGeometryTransform(m_geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    } else {
        MotionSteps ms = motion_steps(m_to_world, motion);
        rtcSetGeometryTimeStepCount(m_geom, unsigned(ms.keys.size()));
        for (size_t i = 0; i < ms.keys.size(); ++i) {
            const TransformKey &k = ms.keys[i];
            RTCQuaternionDecomposition qd;
            rtcInitQuaternionDecomposition(&qd);
            rtcQuaternionDecompositionSetScale(&qd, k.scale.x, k.scale.y, k.scale.z);
            rtcQuaternionDecompositionSetQuaternion(&qd, float(k.rotation.w), float(k.rotation.x),
                                                    float(k.rotation.y), float(k.rotation.z));
            rtcQuaternionDecompositionSetTranslation(&qd, k.translation.x, k.translation.y, k.translation.z);
            rtcSetGeometryTransformQuaternion(m_geom, unsigned(i), &qd);
        }
        rtcSetGeometryTimeRange(m_geom, ms.embree_begin, ms.embree_end);
    }
    rtcCommitGeometry(m_geom);
    return rtcAttachGeometry(scene, m_geom);
}

Transform Instance::transform_at(float time) const {
    if (!m_to_world.is_animated() || !m_geom) return m_to_world.eval(time);
    float xfm[12];
    rtcGetGeometryTransform(m_geom, m_motion.to_embree(time), RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    Matrix4 m;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) m.m[r][c] = xfm[3 * c + r];
    return Transform(m);
}

void Instance::fill_interaction(const Ray &, float, uint32_t, Vec2f, SurfaceInteraction &) const {
    throw std::logic_error("an instance is intersected through fill_instance_interaction");
}

void Instance::fill_instance_interaction(const Ray &ray, float t, unsigned inner_geom, uint32_t prim, Vec2f b,
                                         SurfaceInteraction &si) const {
    const Transform to_world = transform_at(ray.time), to_local = to_world.inverse();
    // Embree intersects in object space with the untransformed parameter t.
    Ray local = ray;
    local.o = to_local.point(ray.o);
    local.d = to_local.vector(ray.d);
    const Shape *inner = m_group->member(inner_geom);
    si.shape = inner;
    si.instance = this;
    si.prim = prim;
    inner->fill_interaction(local, t, prim, b, si);

    si.p = to_world.point(si.p);
    si.n = normalize(to_world.normal(si.n));
    Normal3f ns = normalize(to_world.normal(si.sh_frame.n));
    Vec3f s = to_world.vector(si.sh_frame.s);
    s = s - ns * dot(ns, s);
    float l = norm(s);
    si.sh_frame = l > 1e-12f ? Frame(s / l, cross(ns, s / l), ns) : Frame(ns);
}

std::pair<Vec3f, Vec3f> surface_uv_partials(const SurfaceInteraction &si) {
    if (!si.shape) return {};
    if (!si.instance) return si.shape->uv_partials(si.prim, si.p);
    const Transform to_world = si.instance->transform_at(si.time);
    const auto [du, dv] = si.shape->uv_partials(si.prim, to_world.inverse().point(si.p));
    return {to_world.vector(du), to_world.vector(dv)};
}

BoundingBox Instance::bounds() const {
    BoundingBox inner = m_group->bounds(), out;
    if (!inner.valid()) return out;
    auto add = [&](const Transform &m) {
        for (int c = 0; c < 8; ++c)
            out.expand(m.point({(c & 1) ? inner.max.x : inner.min.x, (c & 2) ? inner.max.y : inner.min.y,
                                (c & 4) ? inner.max.z : inner.min.z}));
    };
    if (!m_to_world.is_animated()) {
        add(m_to_world.eval(0.f));
        return out;
    }
    const int steps = 64; // rotations may bulge slightly between samples; bounds are informative only
    for (int i = 0; i <= steps; ++i)
        add(m_to_world.eval(lerp(float(i) / steps, m_to_world.t_begin(), m_to_world.t_end())));
    return out;
}

// ---------------------------------------------------------------- Plugins

std::shared_ptr<Object> make_maybe_animated(const Properties &props,
                                            const std::function<std::shared_ptr<Shape>(const Transform &)> &make) {
    AnimatedTransform at = props.get_animated_transform("to_world");
    if (!at.is_animated()) return make(at.eval(0.f));
    std::shared_ptr<Shape> shape = make(Transform());
    if (shape->emitter)
        props.fail("to_world", "an area emitter cannot be attached to an animated shape (its light sampling is static)");
    auto inst = std::make_shared<Instance>(std::make_shared<ShapeGroup>(std::vector{shape}), std::move(at));
    inst->id = shape->id;
    return inst;
}

namespace {

std::shared_ptr<Object> make_shapegroup(const Properties &props, const LoadContext &) {
    std::vector<std::shared_ptr<Shape>> shapes;
    for (const ChildObject *c : props.children_of_kind("shape")) {
        auto s = std::static_pointer_cast<Shape>(c->object);
        if (s->is_shapegroup() || dynamic_cast<const Instance *>(s.get()))
            throw SceneError(c->loc, "a shapegroup cannot contain instances, shapegroups or animated shapes "
                                     "(nested instancing is not supported)");
        if (s->emitter)
            throw SceneError(c->loc, "a shape inside a shapegroup cannot be an area emitter (as in Mitsuba)");
        shapes.push_back(std::move(s));
    }
    if (shapes.empty()) props.fail("", "a shapegroup needs at least one nested <shape>");
    auto g = std::make_shared<ShapeGroup>(std::move(shapes));
    g->id = props.id;
    return g;
}

std::shared_ptr<Object> make_instance(const Properties &props, const LoadContext &) {
    auto children = props.children_of_kind("shape");
    if (children.size() != 1 || !std::static_pointer_cast<Shape>(children[0]->object)->is_shapegroup())
        props.fail("", "an instance needs exactly one <ref> to a shapegroup");
    auto group = std::static_pointer_cast<ShapeGroup>(children[0]->object);
    auto inst = std::make_shared<Instance>(group, props.get_animated_transform("to_world"));
    inst->id = props.id;
    if (props.child_of_kind("bsdf") || props.child_of_kind("emitter"))
        props.fail("", "an instance takes its materials from the shapegroup; it accepts no bsdf or emitter");
    return inst;
}

} // namespace

MVPT_REGISTER_PLUGIN("shape", "shapegroup", make_shapegroup);
MVPT_REGISTER_PLUGIN("shape", "instance", make_instance);

} // namespace mvpt
