// The `mvpath` integrator's XML interface (docs/multiview-path-tracing.md):
//   <integrator type="mvpath">
//     <integer name="max_depth" value="-1"/> <integer name="rr_depth" value="5"/>
//     <boolean name="hide_emitters" value="false"/>          (as for `path`)
//     <string name="estimator" value="balance"/>             balance | weighted (§5)
//     <boolean name="control_variate" value="true"/>         balance + beta (1 - sum W), unbiased
//     <string name="mis_set" value="all"/>                   all | selected (published, biased)
//     <boolean name="select_jacobian" value="false"/>         s_J of §6 (default true with mis_set=selected)
//     <boolean name="select_material" value="false"/>         s_M of §6 (off: see mvpath.h)
//     <string name="tv" value="peak"/>                        peak | montecarlo (§6)
//     <boolean name="adaptive" value="true"/>                 native-sample maps (§8)
//     <integer name="adaptive_warmup" value="4"/> <integer name="adaptive_max" value="16"/>
//     <float name="adaptive_budget" value="1.25"/>           mean native samples per pixel and pass
//     <float name="adaptive_eps" value="0.01"/>              eps of the relative error the maps even out
//     <integer name="rig_cells" value="128"/>                 cells proven to see the rig unblocked (0: off)
//     <integer name="batch_entries" value="4096"/>            pending entries traced and splatted together
//     <string name="splits" value="auto"/>                    light samples and bounces per shared vertex (§7):
//                                                             chosen per render, or <integer ...>: 1-64
//   </integrator>
#include "mvpath.h"

#include "../../core/plugin.h"

namespace mvpt {
namespace {

std::shared_ptr<Object> make_mvpath(const Properties &props, const LoadContext &) {
    const PathConfig pc = read_path_config(props);

    MvConfig cfg;
    std::string est = props.get_string("estimator", "balance");
    if (est == "balance") cfg.estimator = MvEstimator::Balance;
    else if (est == "weighted") cfg.estimator = MvEstimator::Weighted;
    else props.fail("estimator", "'estimator' must be 'balance' or 'weighted', got '" + est + "'");
    cfg.control_variate = props.get_bool("control_variate", true);
    std::string set = props.get_string("mis_set", "all");
    if (set == "all") cfg.mis_selected_only = false;
    else if (set == "selected") cfg.mis_selected_only = true;
    else props.fail("mis_set", "'mis_set' must be 'all' or 'selected', got '" + set + "'");
    cfg.select_jacobian = props.get_bool("select_jacobian", cfg.mis_selected_only);
    cfg.select_material = props.get_bool("select_material", false);
    std::string tv = props.get_string("tv", "peak");
    if (tv == "peak") cfg.tv = MvTotalVariation::PeakRatio;
    else if (tv == "montecarlo") cfg.tv = MvTotalVariation::MonteCarlo;
    else props.fail("tv", "'tv' must be 'peak' or 'montecarlo', got '" + tv + "'");
    cfg.adaptive = props.get_bool("adaptive", true);
    cfg.adaptive_warmup = int(props.get_int_in("adaptive_warmup", 4, 2, INT32_MAX)); // passes
    cfg.adaptive_max = int(props.get_int_in("adaptive_max", 16, 1, 1024));
    cfg.adaptive_budget = props.get_float("adaptive_budget", 1.25f);
    if (!(cfg.adaptive_budget >= 1.f && cfg.adaptive_budget <= float(cfg.adaptive_max)))
        props.fail("adaptive_budget", "'adaptive_budget' must lie in [1, adaptive_max]");
    cfg.adaptive_eps = props.get_float("adaptive_eps", 0.01f);
    if (!(cfg.adaptive_eps >= 0.f && cfg.adaptive_eps < INFINITY))
        props.fail("adaptive_eps", "'adaptive_eps' must be a finite number >= 0");
    cfg.rig_cells = int(props.get_int_in("rig_cells", 128, 0, 1024));
    cfg.batch_entries = int(props.get_int_in("batch_entries", 4096, 1, 1 << 24));
    if (props.is_string("splits")) {
        const std::string word = props.get_string("splits");
        if (word != "auto") props.fail("splits", "'splits' must be 'auto' or an integer in [1, 64], got '" + word + "'");
        cfg.splits = 0; // chosen per render
    } else if (props.has("splits")) {
        cfg.splits = int(props.get_int_in("splits", 1, 1, 64));
    }
    if (props.is_string("delta_splits")) {
        const std::string word = props.get_string("delta_splits");
        if (word != "auto")
            props.fail("delta_splits", "'delta_splits' must be 'auto' or an integer in [1, 64], got '" + word + "'");
        cfg.delta_splits = 0;
    } else if (props.has("delta_splits")) {
        cfg.delta_splits = int(props.get_int_in("delta_splits", 1, 1, 64));
    }
    return std::make_shared<MultiViewPathIntegrator>(pc, cfg);
}

} // namespace

MVPT_REGISTER_PLUGIN("integrator", "mvpath", make_mvpath);

} // namespace mvpt
