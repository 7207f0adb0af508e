// The results CSV of `qm3d batch`: its header (csv_header() and a last "settings" column), the
// settings every row records, the lock that keeps a second batch out, and what --resume reads
// back from it.
#pragma once

#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "qm3d/scoring/score.h"

namespace qm3d::study {

/// csv_header() and ",settings".
std::string batch_header(const std::vector<std::string>& value_names = {});

/// The options a batch scores with, as one field: "key=value" items separated by spaces and
/// sorted (metric options as given, direction, model=METRIC:w1/.../w8), or "defaults". The
/// data folder and thread counts are not settings (they do not change a score).
std::string batch_settings(const scoring::ScoreRequest& request);

/// "radius: 0.01 in FILE, 0.02 in this run; ..." for the items of two settings that differ.
std::string settings_difference(const std::string& recorded, const std::string& current,
                                const std::string& file);

/// (reference, distorted, metric): what identifies a row.
using RowKey = std::tuple<std::string, std::string, std::string>;

/// The results file, opened for appending (created when absent) and locked (flock, exclusive,
/// not waiting) for as long as this object lives.
class LockedResults {
 public:
  /// @throws InputError "FILE: is being written by another qm3d batch (pid N)" when locked, or
  /// when it cannot be opened.
  explicit LockedResults(const std::filesystem::path& path);
  ~LockedResults();
  LockedResults(const LockedResults&) = delete;
  LockedResults& operator=(const LockedResults&) = delete;

  /// Empties the file (--overwrite).
  void truncate();
  /// Replaces the whole content, atomically (a temporary file renamed over the path, locked
  /// before it is renamed), keeping the lock.
  void replace(const std::string& text);
  /// Appends one line with a single write(2), so that a kill never leaves half a row.
  void write_line(const std::string& line);
  bool is_regular() const { return regular_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::vector<int> replaced_;  // descriptors of replaced versions, still locked
  bool regular_ = true;
  std::mutex mutex_;
};

/// What --resume reads from an existing results file.
struct ResumeState {
  std::set<RowKey> done;    ///< rows not to score again
  std::string kept_text;    ///< the file without the rows to score again (--retry-failed)
  std::size_t retried = 0;  ///< error rows dropped for scoring again
  bool has_header = false;  ///< false: the file is empty
  bool widened = false;     ///< a tidy file (tidy_results()): kept_text has the full header
};

/// Reads `text`, the content of `file` (a trailing partial line already cut). @throws
/// InputError when it is not a qm3d batch results file (its first line is not batch_header())
/// or a row was scored with other settings than `settings` (naming what differs).
ResumeState read_resume(const std::string& text, const std::string& file,
                        const std::string& settings, bool retry_failed,
                        const std::vector<std::string>& value_names = {});

/// The results text tidied for reading at the end of a batch: its rows in `order` (the list's
/// (pair, metric) order; rows not in it after those, in file order), and of the named-value
/// columns of `value_names` only those of the metrics its rows name. read_resume() widens such
/// a file back to the full header.
std::string tidy_results(const std::string& text, const std::vector<RowKey>& order,
                         const std::vector<std::string>& value_names);

/// The same, the value names read from the text's header (`qm3d merge`'s output).
std::string tidy_results(const std::string& text, const std::vector<RowKey>& order);

/// The number of rows of a results text whose status is not "ok".
std::size_t count_error_rows(const std::string& text);

}  // namespace qm3d::study
