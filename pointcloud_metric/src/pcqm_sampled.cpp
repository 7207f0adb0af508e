// "pcqm_sampled": PCQM on clouds sampled from the surfaces of two meshes, both sampled alike
// (same count or density, same seed), so that meshes can be scored with a point-cloud metric.
#include <algorithm>
#include <cmath>
#include <future>

#include "pcqm_spec.h"
#include "qm3d/pointcloud/metrics.h"

namespace qm3d::pointcloud {
namespace {

// PCQM's curvature radius, 0.004 of the box (reference -r), is meant for clouds of about a
// million points (the PCQM paper's stimuli); on 20,000 samples nearly every point has fewer than
// six neighbours within it and every curvature fit is underdetermined. The default radius of
// pcqm_sampled is the reference's at the samples' density: the same expected number of points
// within the radius as 0.004 gives on a million samples of the surface.
constexpr double kReferenceRadiusRel = 0.004;
constexpr double kReferenceCloudPoints = 1e6;

double radius_for_samples(std::size_t samples) {
  const double r = kReferenceRadiusRel *
                   std::sqrt(kReferenceCloudPoints / std::max<double>(double(samples), 1.0));
  return std::min(r, kMaxRadiusRel);
}

}  // namespace

MetricSpec pcqm_sampled_spec(SurfaceSampler sample) {
  MetricSpec s;
  s.name = "pcqm_sampled";
  s.title = "PCQM_SAMPLED";
  s.reproduces = "MEPP-team/PCQM @ 2a2c410 (on qm3d's own surface samples)";
  s.summary = "PCQM on clouds sampled from the surfaces of two meshes (both sampled alike: same "
              "count or density, same seed; textured OBJ sampled from its texture)";
  s.applies_to = AppliesTo::kMeshes;
  s.reads = Input::Kind::kMesh;
  s.default_direction = kPcqmDefaultDirection;
  s.direction_help = "as for pcqm, on the sampled clouds";
  s.takes_model = true;
  s.model_metric = "pcqm";
  s.per_element_on_input = false;
  s.options = detail::pcqm_option_specs();
  for (OptionSpec& o : s.options) {
    if (o.name != "radius") continue;
    o.default_value = 0.0;
    o.min = 0;
    o.help =
        "Curvature radius as a fraction of the bounding box; 0 = the reference's 0.004 at "
        "the samples' density: 0.004 * sqrt(1e6 / samples) (0.028 for 20000 samples)";
  }
  s.options.push_back({"points", "Samples per mesh (when no density is given)",
                       kDefaultSampledPoints, {}, 1, 1e12});
  s.options.push_back({"density",
                       "Samples per unit area (the mesh's units^-2), instead of points (0 = use "
                       "points)",
                       0.0, {}, 0, 1e300});
  s.options.push_back({"seed", "Seed of the sampling (same seed, same cloud)", 1, {}, 0, 1.8e19});
  s.run = [sample](const MetricSpec&, const Input& ref, const Input& dist, const RunOptions& run,
                   const OptionValues& values) {
    SurfaceSampling sampling;
    sampling.density = values.at("density").get<double>();
    sampling.points = sampling.density > 0 ? 0 : values.at("points").get<std::size_t>();
    sampling.seed = values.at("seed").get<std::uint64_t>();
    auto ref_task = std::async(run.threads == 1 ? std::launch::deferred : std::launch::async,
                               [&] { return sample(ref, sampling); });
    const ColoredCloud d = sample(dist, sampling);
    const ColoredCloud r = ref_task.get();
    if (run.inputs_done) run.inputs_done();  // the meshes are not read below
    OptionValues given = values;
    if (given.at("radius").get<double>() == 0)
      given["radius"] = radius_for_samples(r.positions.size());
    PcqmOptions options = detail::pcqm_options(run, given);
    options.inputs_done = nullptr;  // the samples are this function's own
    MetricResult result = compute_pcqm(r, d, options);
    result.metric = "pcqm_sampled";
    result.provenance.options["sampling"] = {
        {"points", sampling.points}, {"density", sampling.density}, {"seed", sampling.seed}};
    return result;
  };
  return s;
}

}  // namespace qm3d::pointcloud
