// Microfacet distributions and quadrature: normalisation of D and of the
// visible-normal density, and exactness of the Gauss-Legendre rule.
#include "mvpt/core/quadrature.h"
#include "mvpt/render/fresnel.h"
#include "mvpt/render/microfacet.h"

#include <gtest/gtest.h>

using namespace mvpt;

namespace {

/// Integrate f over the upper hemisphere on a (cos theta, phi) midpoint grid.
template <typename F> double integrate_hemisphere(F f, int n = 800) {
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            float c = (i + 0.5f) / n, phi = 2.f * Pi * (j + 0.5f) / (2 * n), s = std::sqrt(1.f - c * c);
            sum += f(Vec3f(s * std::cos(phi), s * std::sin(phi), c));
        }
    return sum * (1.0 / n) * (Pi / n);
}

} // namespace

TEST(Quadrature, GaussLegendreIsExactForPolynomials) {
    std::vector<float> x, w;
    gauss_legendre(7, x, w);
    double s0 = 0, s6 = 0, s13 = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        s0 += w[i];
        s6 += w[i] * std::pow(x[i], 6);
        s13 += w[i] * std::pow(x[i], 12);
    }
    EXPECT_NEAR(s0, 2.0, 1e-6);
    EXPECT_NEAR(s6, 2.0 / 7.0, 1e-6);
    EXPECT_NEAR(s13, 2.0 / 13.0, 1e-6);
}

TEST(Microfacet, ProjectedAreaAndVisibleNormalsAreNormalised) {
    for (auto type : {MicrofacetType::GGX, MicrofacetType::Beckmann})
        for (auto [au, av] : {std::pair{0.3f, 0.3f}, std::pair{0.2f, 0.6f}}) {
            MicrofacetDistribution d(type, au, av, true);
            // \int D(m) cos(theta_m) dm = 1 [Walter et al. 2007, eq. 4].
            EXPECT_NEAR(integrate_hemisphere([&](Vec3f m) { return d.eval(m) * m.z; }), 1.0, 2e-3);
            // The visible-normal density integrates to one for any wi [Heitz 2014, eq. 2 with Smith G1].
            Vec3f wi = normalize(Vec3f(0.6f, 0.3f, 0.5f));
            EXPECT_NEAR(integrate_hemisphere([&](Vec3f m) { return d.pdf(wi, m); }), 1.0, 5e-3);
        }
}

TEST(Fresnel, DiffuseReflectanceFitMatchesIntegral) {
    for (float eta : {0.7f, 1.33f, 1.5f, 2.0f}) {
        const int n = 20000;
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            float c = (i + 0.5f) / n;
            sum += 2.0 * c * fresnel_dielectric(c, eta).F / n;
        }
        EXPECT_NEAR(fresnel_diffuse_reflectance(eta), sum, 0.01 * sum + 1e-3) << "eta = " << eta;
    }
}
