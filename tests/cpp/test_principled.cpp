// principled / principledthin: sample-for-sample agreement with Mitsuba 3.9.1
// (same random numbers give the same lobe, direction, pdf and weight), the
// roughness() heuristic, and parameter errors.
#include "mvpt/render/bsdf.h"
#include "mvpt/loader/xml_parser.h"

#include <gtest/gtest.h>

using namespace mvpt;

namespace {

std::shared_ptr<Bsdf> load_bsdf(const std::string &xml) {
    XmlNode root = parse_scene_string("<scene version=\"3.0.0\">" + xml + "</scene>", ".", {});
    SceneTree tree = instantiate_scene(root, ".");
    for (auto &c : tree.props.children())
        if (c.kind == "bsdf") return std::static_pointer_cast<Bsdf>(c.object);
    return nullptr;
}

SurfaceInteraction local_si() {
    SurfaceInteraction si;
    si.uv = {0.5f, 0.5f};
    si.n = {0, 0, 1};
    return si;
}

struct Expected {
    Vec3f wi;
    float u1;
    Vec2f u2;
    Vec3f wo;
    float pdf;
    Color3f weight;
    uint32_t type;
};

void check_samples(const Bsdf &bsdf, const std::vector<Expected> &table) {
    SurfaceInteraction si = local_si();
    for (const Expected &e : table) {
        auto [bs, w] = bsdf.sample({}, si, normalize(e.wi), e.u1, e.u2);
        SCOPED_TRACE(testing::Message() << "u1 = " << e.u1 << ", wi.z = " << e.wi.z);
        EXPECT_EQ(bs.sampled_type, e.type);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(bs.wo[k], e.wo[k], 2e-5f);
        // Densities: 1e-4 relative (float32 rounding of wi and of refracted directions).
        EXPECT_NEAR(bs.pdf, e.pdf, 1e-4f * e.pdf);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(w[k], e.weight[k], 1e-4f * e.weight[k] + 1e-7f);
    }
}

} // namespace

// Reference values: mi.load_dict(...).sample(BSDFContext(), si, u1, u2) in Mitsuba 3.9.1 scalar_rgb.
TEST(Principled, SamplesMatchMitsuba) {
    auto bsdf = load_bsdf(R"(<bsdf type="principled">
        <float name="metallic" value="0.3"/> <float name="spec_trans" value="0.4"/>
        <float name="clearcoat" value="0.7"/> <float name="clearcoat_gloss" value="0.3"/>
        <float name="anisotropic" value="0.5"/> <float name="roughness" value="0.4"/>
        <rgb name="base_color" value="0.8, 0.4, 0.2"/></bsdf>)");
    ASSERT_TRUE(bsdf);
    const Vec3f front(0.3f, -0.2f, 0.7f), back(-0.5f, 0.4f, -0.6f);
    check_samples(*bsdf, {
        {front, 0.05f, {0.3f, 0.7f}, {-0.28284270f, 0.28284273f, 0.91651517f}, 1.6751494f, {0.56672478f, 0.32281736f, 0.20086367f}, 2},
        {front, 0.3f, {0.6f, 0.2f}, {-0.51736969f, 0.15492208f, 0.84162217f}, 1.0751603f, {0.58075279f, 0.32728627f, 0.20055300f}, 8},
        {front, 0.45f, {0.8f, 0.9f}, {-0.16568419f, 0.18346502f, -0.96896303f}, 2.4027660f, {0.63375419f, 0.44813186f, 0.31687710f}, 16},
        {front, 0.7f, {0.15f, 0.4f}, {-0.13540676f, 0.42549005f, 0.89477545f}, 0.52741063f, {0.64360774f, 0.35608163f, 0.21231857f}, 8},
        {front, 0.95f, {0.55f, 0.35f}, {-0.23954818f, 0.20591751f, 0.94879633f}, 1.4057032f, {0.58408743f, 0.32998231f, 0.20292978f}, 8},
        {back, 0.05f, {0.3f, 0.7f}, {0.56511205f, -0.50607765f, -0.65156251f}, 3.7269273f, {0.27701893f, 0.27701893f, 0.27701893f}, 8},
        {back, 0.3f, {0.6f, 0.2f}, {0.71942639f, -0.62954974f, 0.29341552f}, 2.6050768f, {0.52184904f, 0.36900300f, 0.26092452f}, 16},
        {back, 0.45f, {0.8f, 0.9f}, {0.79673564f, -0.42069879f, -0.43384862f}, 1.2784492f, {0.26900256f, 0.26900256f, 0.26900256f}, 8},
    });
}

TEST(PrincipledThin, SamplesMatchMitsuba) {
    auto bsdf = load_bsdf(R"(<bsdf type="principledthin">
        <float name="spec_trans" value="0.6"/> <float name="diff_trans" value="0.8"/>
        <float name="roughness" value="0.35"/> <float name="eta" value="1.4"/>
        <float name="anisotropic" value="0.3"/> <rgb name="base_color" value="0.8, 0.4, 0.2"/></bsdf>)");
    ASSERT_TRUE(bsdf);
    const Vec3f front(0.3f, -0.2f, 0.7f), back(-0.5f, 0.4f, -0.6f);
    check_samples(*bsdf, {
        {front, 0.05f, {0.3f, 0.7f}, {-0.40098244f, 0.32269236f, 0.85736948f}, 1.4272640f, {0.09174982f, 0.07339346f, 0.06421530f}, 8},
        {front, 0.3f, {0.6f, 0.2f}, {-0.33273944f, 0.22386196f, -0.91606247f}, 7.0591793f, {1.5494552f, 0.77472758f, 0.38736379f}, 16},
        {front, 0.7f, {0.15f, 0.4f}, {-0.68244958f, -0.15576464f, 0.71414286f}, 0.083272874f, {0.54448599f, 0.28242713f, 0.15139775f}, 2},
        {front, 0.95f, {0.55f, 0.35f}, {-0.07764574f, 0.28977773f, -0.95393920f}, 0.13684466f, {1.2870090f, 0.64350450f, 0.32175225f}, 4},
        {back, 0.45f, {0.8f, 0.9f}, {0.64215332f, -0.45163912f, 0.61940384f}, 3.7360361f, {1.5256293f, 0.76281464f, 0.38140732f}, 16},
        {back, 0.7f, {0.15f, 0.4f}, {0.68244958f, 0.15576464f, -0.71414286f}, 0.063968234f, {0.69156092f, 0.35056981f, 0.18007427f}, 2},
    });
}

TEST(Principled, RoughnessHeuristic) {
    SurfaceInteraction si = local_si();
    // Pure metal: the only lobe is GGX with alpha = roughness^2.
    auto metal = load_bsdf(R"(<bsdf type="principled"><float name="metallic" value="1"/>
        <float name="roughness" value="0.3"/></bsdf>)");
    EXPECT_NEAR(metal->roughness(si), 0.09f, 1e-6f);
    // Mostly diffuse: close to 1, but pulled down by the specular lobe.
    auto plastic = load_bsdf(R"(<bsdf type="principled"><float name="roughness" value="0.1"/></bsdf>)");
    float r = plastic->roughness(si);
    EXPECT_GT(r, 0.4f);
    EXPECT_LT(r, 0.6f);
    // Thin sheet with only specular lobes.
    auto thin = load_bsdf(R"(<bsdf type="principledthin"><float name="spec_trans" value="1"/>
        <float name="roughness" value="0.2"/><float name="eta" value="1"/></bsdf>)");
    EXPECT_NEAR(thin->roughness(si), 0.04f * 0.5f + 0.3f * 0.3f * 0.04f * 0.5f, 1e-6f);
}

TEST(Principled, ParameterErrors) {
    EXPECT_THROW(load_bsdf(R"(<bsdf type="principled"><float name="eta" value="1.5"/>
        <float name="specular" value="0.5"/></bsdf>)"), SceneError);
    EXPECT_THROW(load_bsdf(R"(<bsdf type="principled"><float name="eta" value="-1"/></bsdf>)"), SceneError);
    EXPECT_THROW(load_bsdf(R"(<bsdf type="principled"><float name="shine" value="1"/></bsdf>)"), SceneError);
    EXPECT_THROW(load_bsdf(R"(<bsdf type="principledthin"><float name="diffuse_reflectance_sampling_rate" value="-1"/></bsdf>)"), SceneError);
}

TEST(Principled, FlagsFollowEnabledLobes) {
    auto opaque = load_bsdf(R"(<bsdf type="principled"><float name="spec_trans" value="0"/></bsdf>)");
    EXPECT_EQ(opaque->flags() & BsdfGlossyTransmission, 0u);
    auto glass = load_bsdf(R"(<bsdf type="principled"><float name="spec_trans" value="0.5"/></bsdf>)");
    EXPECT_NE(glass->flags() & BsdfGlossyTransmission, 0u);
    auto thin = load_bsdf(R"(<bsdf type="principledthin"/>)");
    EXPECT_NE(thin->flags() & BsdfDiffuseTransmission, 0u);
}
