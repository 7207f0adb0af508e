// `qm3d batch`: scores every pair of a list, appending one CSV row per pair as soon as it is done.
#pragma once

#include <filesystem>
#include <optional>

#include "commands.h"
#include "shard.h"

namespace qm3d::app {

struct BatchOptions {
  std::filesystem::path list;    ///< CSV with columns reference,distorted[,metric]; metric is
                                 ///< cmdm, msdm2, pcqm, pcqm_sampled, compare (one row
                                 ///< per metric of compare_metrics) or auto (CMDM for
                                 ///< meshes, else PCQM)
  std::filesystem::path output;  ///< results CSV (appended to, row by row)
  int jobs = 1;                  ///< pairs scored at the same time
  int threads = 0;               ///< total threads (0 = all cores), shared among the jobs
  bool resume = false;           ///< skip pairs already in `output`
  bool overwrite = false;        ///< replace an existing `output`
  bool quiet = false;            ///< no progress on stderr
  std::optional<Shard> shard;    ///< score only this part of the pairs (--shard K/N)
  MetricOptions metrics;
};

/// Runs the batch. Returns 0 when every pair succeeded and 2 when some failed (their rows carry
/// the error). Throws InputError / FormatError when the list or the output cannot be used.
int run_batch(const BatchOptions& options);

}  // namespace qm3d::app
