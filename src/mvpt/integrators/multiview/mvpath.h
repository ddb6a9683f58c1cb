// Multi-view path tracing (docs/multiview-path-tracing.md; Fraboni et al., EGSR 2019):
// the configuration of the `mvpath` integrator. The work itself is split by concept:
// mv_shift.* (prefix shift and validity tests, §3–§4), mv_selection.* (which views
// share, §6), mv_context.* (what a pass's samples share), mv_sample.* (one native sample:
// densities §5, shared shading §7), mv_splat.* (its contributions splatted),
// mv_estimator.h (a pixel's estimate in a pass, §5), mv_adaptive.* (native-sample maps, §8);
// renderer/multiview_passes.cpp runs the passes, renderer/film.* accumulates them.
#pragma once

#include "../path/path.h"

#include <memory>
#include <string>

namespace mvpt {

/// Estimator of §5.
enum class MvEstimator {
    Balance,  ///< unbiased: contributions L / D_k, D_k summed over every valid view
    Weighted, ///< MWIS ratio estimator: sum W L / sum W with W = 1 / D_k (consistent)
};

/// How total variation between two lobes is estimated for the material similarity (§6).
enum class MvTotalVariation {
    PeakRatio,  ///< density ratio at both lobes' mirror directions (default)
    MonteCarlo, ///< fixed quasi-random estimate of 1/2 int |rho_l - rho_k| (slow, for studies)
};

struct MvConfig {
    MvEstimator estimator = MvEstimator::Balance;
    /// Balance estimator: add the control variate beta (1 - sum W) per pixel and pass (see
    /// mv_estimator.h); unbiased, removes the noise of the number of contributions.
    bool control_variate = true;
    /// Sum D_k only over the views selected for the sample (the published code; biased).
    bool mis_selected_only = false;
    /// Selection terms of §6 (each 1 when off). s_J is off by default except with
    /// mis_set=selected (the published method): with D_k summed over every valid view the
    /// balance weights already bound each contribution by L_k / n_k, and a selection draw only
    /// discards shares whose visibility was traced anyway (docs/multiview-path-tracing.md §6:
    /// 6 % lower error per native sample on the glossy Cornell box, 4 % on the light field).
    bool select_jacobian = false;
    /// Off by default: it costs two BSDF densities per pair of views (O(V^2) per sample) and
    /// on our scenes it lowered efficiency (docs/multiview-path-tracing.md §6: on the 5x5
    /// light field 3.4x, on the glossy Cornell box 1.5x, with equal or higher error).
    bool select_material = false;
    MvTotalVariation tv = MvTotalVariation::PeakRatio;
    /// Adaptive native-sample maps across passes (§8).
    bool adaptive = true;
    /// Passes with one native sample per pixel before the maps adapt.
    int adaptive_warmup = 4;
    /// Upper bound of a pixel's native samples in one pass.
    int adaptive_max = 16;
    /// Mean native samples per pixel in an adaptive pass (the freedom the maps have: n >= 1).
    float adaptive_budget = 1.25f;
    /// The maps even out (x - r)^2 / (r^2 + eps) with eps = max(adaptive_eps, (view mean / 10)^2):
    /// by default the eps of the relMSE that `mvpt compare` and the benchmarks report, so
    /// that pixels darker than ~0.1 count by absolute error there as well.
    float adaptive_eps = 0.01f;
    /// Splits of the shared vertex (docs/multiview-path-tracing.md §7, "Splitting"): light
    /// samples and bounces per native sample, each shared by every sharing view and weighted
    /// 1/splits. The shifts, visibility and densities D of the first vertex are paid once.
    /// 0 (`auto`, the default): chosen per render from a pilot (mv_split_choice.h).
    int splits = 0;
    /// Paths traced on from a purely specular first vertex (glass, a mirror), which no view can
    /// share, each weighted 1/delta_splits: such a pixel's samples are its own, as in path
    /// tracing, and far cheaper than a shared one (docs/multiview-path-tracing.md, "Where
    /// nothing can be shared"). 0 (`auto`, the default): chosen with the splits from the pilot.
    int delta_splits = 0;
    /// Visibility cells (accel/rig_visibility.h) along the scene's longest side; 0 turns them
    /// off. Static scenes and cameras only.
    int rig_cells = 128;
    /// Entries (one per sharing view and split of a native sample, 44 bytes each) after which
    /// the pending samples of a tile are traced and splatted (mv_native_samples), so that the
    /// entries are read back from the core's own cache: about 180 KiB by default. Images do
    /// not depend on it.
    int batch_entries = 4096;
};

/// The `mvpath` integrator: path tracing whose first vertex is shared between views.
/// As an ordinary per-ray integrator (`li`) it is the path tracer with the same settings;
/// the multi-view renderer uses `path()` for suffixes and `config()` for the method.
class MultiViewPathIntegrator final : public Integrator {
public:
    MultiViewPathIntegrator(const PathConfig &path_cfg, const MvConfig &cfg)
        : m_path(std::make_shared<PathIntegrator>(path_cfg)), m_cfg(cfg) {}
    Spectrum li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const override {
        return m_path->li(scene, ray, sampler, counters);
    }
    std::string name() const override { return "mvpath"; }
    const PathIntegrator &path() const { return *m_path; }
    const MvConfig &config() const { return m_cfg; }

private:
    std::shared_ptr<PathIntegrator> m_path;
    MvConfig m_cfg;
};

/// The multi-view settings that `integrator` asks for: an mvpath's own, else the defaults.
inline MvConfig multiview_config(const Integrator &integrator) {
    auto *mv = dynamic_cast<const MultiViewPathIntegrator *>(&integrator);
    return mv ? mv->config() : MvConfig{};
}

} // namespace mvpt
