#include "merge_command.h"

#include <iostream>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/study/merge.h"

namespace qm3d::app {
using namespace qm3d::study;  // NOLINT: the merge this command drives
namespace {

// At most this many pairs are named per kind of problem; the rest are counted.
constexpr std::size_t kMaxListed = 20;

void print_list(const std::string& prefix, const std::vector<std::string>& items) {
  for (std::size_t i = 0; i < items.size() && i < kMaxListed; ++i) {
    std::cerr << prefix << items[i] << "\n";
  }
  if (items.size() > kMaxListed) {
    std::cerr << prefix << "... and " << items.size() - kMaxListed << " more\n";
  }
}

// The problems merge found, on stderr (warnings unless `quiet`); throws when nothing may be
// written: conflicting rows, or missing rows without --partial.
void report_problems(const MergeCommand& c, const MergeResult& m, bool quiet) {
  if (!quiet) {
    print_list("qm3d: warning: ", m.warnings);
    print_list("qm3d: warning: duplicated: ", m.duplicates);
    print_list("qm3d: warning: not in " + c.list + ", dropped: ", m.unexpected);
    print_list("merge: failed: ", m.failed);
  }
  print_list("merge: missing: ", m.missing);
  print_list("merge: conflicting rows: ", m.conflicts);
  if (!m.conflicts.empty()) {
    throw FormatError(std::to_string(m.conflicts.size()) +
                      " pairs have conflicting rows in the shard results (listed above); "
                      "nothing written to " +
                      c.output);
  }
  if (!m.missing.empty() && !c.partial) {
    throw InputError(std::to_string(m.missing.size()) + " of " +
                     std::to_string(m.rows.size() + m.missing.size()) +
                     " rows are in no shard result (listed above: did every shard finish? "
                     "rerun a shard with --resume); nothing written to " +
                     c.output + " (--partial writes the rows found)");
  }
}

int run_merge(const MergeCommand& c, bool quiet) {
  const std::vector<ResultKey> expected = expected_rows(c.list, c.output);
  const ShardResults inputs = read_shard_results(c.inputs, c.output, c.partial);
  print_list("merge: missing shard results: ", inputs.missing);
  if (inputs.files.empty()) throw InputError("none of the shard results exists; nothing written");
  const MergeResult m = merge_results(expected, inputs.files);
  report_problems(c, m, quiet);
  const std::string text = merged_text(m);
  write_file_atomically(c.output, [&](std::ostream& out) { out << text; });
  if (!quiet) {
    std::cerr << "merge: " << m.rows.size() << " rows from " << m.files << " files ("
              << m.rows.size() - m.failed.size() << " ok, " << m.failed.size() << " failed, "
              << m.missing.size() << " missing) written to " << c.output << "\n";
  }
  return m.failed.empty() && m.missing.empty() && inputs.missing.empty() ? 0 : 2;
}

}  // namespace

std::unique_ptr<MergeCommand> add_merge_command(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common) {
  auto c = std::make_unique<MergeCommand>();
  c->merge = app.add_subcommand(
      "merge",
      "Join the results of `qm3d batch LIST --shard K/N` runs into the rows one `qm3d batch "
      "LIST` would have written, in LIST's order. Missing, duplicated, conflicting and failed "
      "pairs are reported on stderr (a row whose status is ok but whose score is neither a finite "
      "number nor inf is written as an error row); rows scored with other settings are refused; "
      "exit code 2 when a pair is missing, conflicts or failed");
  add_common(c->merge);
  c->merge
      ->add_option("SHARD_RESULTS", c->inputs, "Results CSVs of the shards (e.g. out/OUT_*.csv)")
      ->required();
  c->merge->add_option("-o,--output", c->output, "Merged results CSV (written atomically)")
      ->required()
      ->type_name("RESULTS.csv");
  c->merge
      ->add_option("--list", c->list,
                   "The list the shards scored: gives the rows expected and their order")
      ->required()
      ->type_name("LIST.csv");
  c->merge->add_flag("--partial", c->partial,
                     "Write the rows found even when some rows or whole shard results are missing "
                     "(each is named on stderr; exit code still 2)");
  return c;
}

std::optional<int> run_merge_command(const MergeCommand& command, bool quiet) {
  if (!command.merge->parsed()) return std::nullopt;
  return run_merge(command, quiet);
}

void add_shard_option(CLI::App* batch_cmd, std::optional<Shard>& shard) {
  const CLI::Validator valid_shard(
      [](std::string& text) {
        try {
          parse_shard(text);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      },
      "", "shard");
  batch_cmd
      ->add_option_function<std::string>(
          "--shard", [&shard](const std::string& text) { shard = parse_shard(text); },
          "Score only part K of N (K = 0..N-1, e.g. $SLURM_ARRAY_TASK_ID/N): the list's pairs "
          "are split into N parts of about equal total file size, the same on every run; give "
          "each part its own RESULTS and join them with `qm3d merge`")
      ->type_name("K/N")
      ->check(valid_shard);
}

}  // namespace qm3d::app
