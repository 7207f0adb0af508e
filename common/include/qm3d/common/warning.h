// Warnings a user reads: one line of at most kMaxWarningLine characters that names the cause and
// the remedy; what does not fit on it goes into the JSON (`warning_details`, result_io.h).
//
// Example:
//   add_warning(result, make_warning(file, "12 faces repeat a vertex", "dropped",
//                                    "the faces' indices: ..."));
//   // result.warnings: {"mesh.off: 12 faces repeat a vertex; dropped"}
//   // result.warning_details: {{"mesh.off: 12 faces ...; dropped", "the faces' indices: ..."}}
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace qm3d {

struct MetricResult;

/// The longest warning line the tool prints (and a test checks on every metric and reader).
inline constexpr std::size_t kMaxWarningLine = 160;

/// One warning: `line` for the terminal, `details` (empty: none) for the JSON.
struct Warning {
  std::string line;
  std::string details;
};

/// "SUBJECT: CAUSE; REMEDY" (an empty subject or remedy is left out with its separator). A line
/// longer than kMaxWarningLine has its subject (a file path) shortened to its file name (a long
/// one to "..." and its last 37 characters), the full subject then opening `details`; still
/// longer, the line is cut at a word and ends with kWarningCut, the whole line in `details`.
Warning make_warning(const std::string& subject, const std::string& cause,
                     const std::string& remedy = {}, std::string details = {});

/// A line written without make_warning, made to fit: longer than kMaxWarningLine, each of
/// `paths` in it is replaced by its file name; still longer, it is cut at a word boundary and
/// ends with kWarningCut, the whole line becoming its details.
Warning fit_warning(const std::string& line, const std::vector<std::string>& paths = {});

/// What a cut line ends with.
inline constexpr const char* kWarningCut = " ... (more in --json)";

/// Appends w.line to result.warnings (once: a line already there is not repeated) and, when it
/// has details, {line, details} to result.warning_details.
void add_warning(MetricResult& result, Warning w);

/// fit_warning on every line of result.warnings, keeping details already there (run_metric
/// calls it last, with the inputs' names as `paths`).
void fit_warnings(MetricResult& result, const std::vector<std::string>& paths);

}  // namespace qm3d
