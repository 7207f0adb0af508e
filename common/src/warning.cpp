#include "qm3d/common/warning.h"

#include <algorithm>
#include <filesystem>
#include <utility>

#include "qm3d/common/result.h"

namespace qm3d {
namespace {

// A subject (file name) longer than this keeps its last characters after "...".
constexpr std::size_t kLongestSubject = 40;

std::string joined(const std::string& subject, const std::string& cause,
                   const std::string& remedy) {
  std::string line = subject.empty() ? cause : subject + ": " + cause;
  if (!remedy.empty()) line += "; " + remedy;
  return line;
}

std::string file_name(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  return name.empty() ? path : name;
}

std::string replaced_all(std::string s, const std::string& from, const std::string& to) {
  if (from.empty() || from == to) return s;
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

/// `line` cut at the last space that leaves room for kWarningCut.
std::string cut(const std::string& line) {
  const std::size_t room = kMaxWarningLine - std::string(kWarningCut).size();
  std::size_t at = line.rfind(' ', room);
  if (at == std::string::npos || at < room / 2) at = room;
  while (at > 0 && (line[at - 1] == ' ' || line[at - 1] == ',' || line[at - 1] == ';')) --at;
  return line.substr(0, at) + kWarningCut;
}

std::string with_details(const std::string& first, const std::string& details) {
  if (details.empty() || first.empty()) return first + details;
  return first + "\n" + details;
}

}  // namespace

Warning make_warning(const std::string& subject, const std::string& cause,
                     const std::string& remedy, std::string details) {
  std::string line = joined(subject, cause, remedy);
  if (line.size() <= kMaxWarningLine) return {std::move(line), std::move(details)};
  std::string shorter = file_name(subject);
  if (shorter.size() > kLongestSubject) {
    shorter = "..." + shorter.substr(shorter.size() - (kLongestSubject - 3));
  }
  line = joined(shorter, cause, remedy);
  if (shorter != subject) details = with_details("file: " + subject, details);
  if (line.size() > kMaxWarningLine) {
    details = with_details(joined(subject, cause, remedy), details);
    line = cut(line);
  }
  return {std::move(line), std::move(details)};
}

Warning fit_warning(const std::string& line, const std::vector<std::string>& paths) {
  if (line.size() <= kMaxWarningLine) return {line, {}};
  std::string shorter = line;
  for (const std::string& p : paths) shorter = replaced_all(shorter, p, file_name(p));
  if (shorter.size() <= kMaxWarningLine) return {shorter, line};
  return {cut(shorter), line};
}

void add_warning(MetricResult& result, Warning w) {
  auto& lines = result.warnings;
  if (std::find(lines.begin(), lines.end(), w.line) != lines.end()) return;
  lines.push_back(w.line);
  if (!w.details.empty()) result.warning_details.push_back({w.line, std::move(w.details)});
}

void fit_warnings(MetricResult& result, const std::vector<std::string>& paths) {
  for (std::string& line : result.warnings) {
    if (line.size() <= kMaxWarningLine) continue;
    Warning w = fit_warning(line, paths);
    for (auto& d : result.warning_details) {
      if (d.warning == line) d.warning = w.line;
    }
    const bool has = std::any_of(result.warning_details.begin(), result.warning_details.end(),
                                 [&w](const WarningDetails& d) { return d.warning == w.line; });
    if (!has) result.warning_details.push_back({w.line, w.details});
    line = std::move(w.line);
  }
}

}  // namespace qm3d
