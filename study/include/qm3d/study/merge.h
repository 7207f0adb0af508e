// `qm3d merge`'s steps: the rows a list expects, the shard results read, the merged file's text
// (merge_results, shard.h, joins them).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/study/shard.h"

namespace qm3d::study {

/// The rows one `qm3d batch LIST` writes, in its order (batch_metrics of each pair). Throws
/// InputError when `list` is `output` itself, FormatError for a malformed list.
std::vector<ResultKey> expected_rows(const std::filesystem::path& list, const std::string& output);

/// The shard results read for merging.
struct ShardResults {
  std::vector<ResultFile> files;
  std::vector<std::string>
      missing;  ///< with `partial`: "FILE: no such file (...)" per absent input
};

/// Reads the shard results `inputs`. Throws InputError when an input is `output` or is given
/// twice, or (without `partial`) cannot be read; with `partial`, an absent input is listed.
ShardResults read_shard_results(const std::vector<std::string>& inputs, const std::string& output,
                                bool partial);

/// The merged results file: the header and rows of `m`, tidied as a batch's final file (the
/// value columns of the metrics its rows name; the rows are in the list's order already).
std::string merged_text(const MergeResult& m);

}  // namespace qm3d::study
