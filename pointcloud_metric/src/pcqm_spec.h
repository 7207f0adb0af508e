// PCQM's options as registry options, shared by pcqm and pcqm_sampled. Internal.
#pragma once

#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/pointcloud/pcqm.h"

namespace qm3d::pointcloud::detail {

/// radius, knn, rx, bbox with PcqmOptions' defaults.
std::vector<OptionSpec> pcqm_option_specs();
/// PcqmOptions from the run options and the values of pcqm_option_specs().
PcqmOptions pcqm_options(const RunOptions& run, const OptionValues& values);

}  // namespace qm3d::pointcloud::detail
