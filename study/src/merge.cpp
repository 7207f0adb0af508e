#include "qm3d/study/merge.h"

#include <set>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/study/batch.h"
#include "qm3d/study/batch_results.h"

namespace qm3d::study {

namespace fs = std::filesystem;

std::vector<ResultKey> expected_rows(const fs::path& list, const std::string& output) {
  if (same_file(list, output)) {
    throw InputError(output + ": is the list itself (--list and -o name the same file)");
  }
  std::vector<ResultKey> expected;
  for (const ListPair& pair :
       parse_pair_list(read_file_bytes(list, kMaxTableBytes), list.string())) {
    for (const std::string& metric : batch_metrics(pair, list)) {
      expected.push_back({pair.reference, pair.distorted, metric});
    }
  }
  return expected;
}

ShardResults read_shard_results(const std::vector<std::string>& inputs, const std::string& output,
                                bool partial) {
  ShardResults r;
  std::set<std::string> seen;
  for (const std::string& input : inputs) {
    if (same_file(input, output)) {
      throw InputError(input + ": is both an input and the output (-o)");
    }
    if (!seen.insert(fs::weakly_canonical(input).string()).second) {
      throw InputError(input + ": given twice");
    }
    if (partial && !fs::exists(input)) {
      r.missing.push_back(input + ": no such file (a shard that did not run?)");
      continue;
    }
    r.files.push_back({input, read_file_bytes(input, kMaxTableBytes)});
  }
  return r;
}

std::string merged_text(const MergeResult& m) {
  std::string text = m.header + "\n";
  for (const std::string& row : m.rows) text += row + "\n";
  return tidy_results(text, {});
}

}  // namespace qm3d::study
