#include "qm3d/study/batch_results.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/result_io.h"
#include "qm3d/study/batch_row.h"

namespace qm3d::study {
using namespace qm3d::scoring;  // NOLINT: the scoring the study runs
namespace {

constexpr std::size_t kStatusColumn = 4;

std::map<std::string, std::string> settings_items(const std::string& settings) {
  std::map<std::string, std::string> items;
  if (settings == "defaults") return items;
  std::istringstream in(settings);
  std::string item;
  while (in >> item) {
    const auto eq = item.find('=');
    items[item.substr(0, eq)] = eq == std::string::npos ? "" : item.substr(eq + 1);
  }
  return items;
}

// The pid holding a flock on (dev, inode), from /proc/locks; 0 when not found.
long lock_holder(const struct stat& st) {
  std::ifstream locks("/proc/locks");
  char id[64];
  std::snprintf(id, sizeof id, "%02x:%02x:%lu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::string line;
  while (std::getline(locks, line)) {
    std::istringstream f(line);
    std::string number, kind, mode, access, pid, where;
    f >> number >> kind;
    if (kind == "->") f >> kind;  // a waiting lock
    f >> mode >> access >> pid >> where;
    if (kind == "FLOCK" && where == id) return std::atol(pid.c_str());
  }
  return 0;
}

[[noreturn]] void throw_busy(const std::filesystem::path& path, const struct stat& st) {
  const long pid = lock_holder(st);
  throw InputError(path.string() + ": is being written by another qm3d batch" +
                   (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                   "; wait for it to end or write to another -o");
}

// Locks `fd`, open on `path`, and checks that `path` still names it (another batch may have
// replaced the file, --retry-failed, between the open and the lock).
void lock(int fd, const std::filesystem::path& path) {
  struct stat opened {};
  ::fstat(fd, &opened);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) throw_busy(path, opened);
    return;  // a file system without locks: nothing to guard with
  }
  struct stat now {};
  if (::stat(path.c_str(), &now) != 0 || now.st_ino != opened.st_ino ||
      now.st_dev != opened.st_dev) {
    throw_busy(path, now);
  }
}

int open_for_append(const std::filesystem::path& path, int extra_flags) {
  // O_NONBLOCK: a FIFO without a reader fails (ENXIO) instead of blocking; cleared after.
  const int fd =
      ::open(path.c_str(),
             O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | extra_flags, 0644);
  if (fd < 0) {
    throw InputError(path.string() + ": cannot open for writing: " + std::strerror(errno));
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  return fd;
}

bool row_failed(const std::vector<std::string>& fields) {
  return fields.size() > kStatusColumn && fields[kStatusColumn] != "ok";
}

// The fields of `line` (under `from`) in the columns `to`, matched by name; a column `from`
// lacks is empty.
std::string remap_row(const std::vector<std::string>& fields, const std::vector<std::string>& from,
                      const std::vector<std::string>& to) {
  std::string row;
  for (std::size_t c = 0; c < to.size(); ++c) {
    const auto it = std::find(from.begin(), from.end(), to[c]);
    const std::size_t k = static_cast<std::size_t>(it - from.begin());
    row += (c ? "," : "") + (it != from.end() && k < fields.size() ? csv_field(fields[k]) : "");
  }
  return row;
}

// Whether `header` is batch_header(value_names) with some value columns left out (a results
// file tidy_results() wrote at the end of a batch).
bool is_tidy_header(const std::vector<std::string>& header, const std::vector<std::string>& full) {
  const std::size_t fixed = csv_split(csv_header()).size();
  if (header.size() <= fixed || header.size() > full.size() || header.back() != "settings" ||
      !std::equal(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(fixed),
                  header.begin())) {
    return false;
  }
  for (const std::string& h : header) {
    if (std::find(full.begin(), full.end(), h) == full.end()) return false;
  }
  return true;
}

// The header check of read_resume: true when the file is a tidy one, whose rows are to be
// widened to the full header.
bool check_header(const std::string& line, const std::string& file,
                  const std::vector<std::string>& value_names) {
  if (line == batch_header(value_names)) return false;
  if (is_tidy_header(csv_split(line), csv_split(batch_header(value_names)))) return true;
  const std::string fixed = "reference,distorted,metric,score,status,error,seconds,";
  if (line.rfind(fixed, 0) == 0 && line.find(",settings") == std::string::npos) {
    throw InputError(file +
                     ": written by an older qm3d (no settings column), so its settings cannot "
                     "be checked: finish it with that version, or start again with --overwrite");
  }
  if (line.rfind(fixed, 0) == 0) {
    throw InputError(file +
                     ": its columns are not this batch's (the list's metrics report other "
                     "named values, e.g. psnr was added or removed, or an older qm3d wrote it): "
                     "resume with the same list and version, or write to another -o");
  }
  throw InputError(file +
                   ": not a qm3d batch results file (its first line is not the header qm3d "
                   "batch writes); --resume only continues such a file");
}

}  // namespace

std::string batch_header(const std::vector<std::string>& value_names) {
  return csv_header(value_names) + ",settings";
}

std::string batch_settings(const ScoreRequest& request) {
  std::vector<std::string> items;
  for (const auto& [name, value] : request.options.items()) {
    items.push_back(name + "=" + (value.is_string() ? value.get<std::string>() : value.dump()));
  }
  if (request.run.direction) items.push_back("direction=" + direction_name(*request.run.direction));
  if (request.read.colour_scale != ColourScale::kAuto) {
    items.push_back(std::string("colour-scale=") + colour_scale_name(request.read.colour_scale));
  }
  if (request.model) {
    std::string weights;
    for (const double w : request.model->weights) {
      weights += (weights.empty() ? "" : "/") + format_double(w);
    }
    items.push_back("model=" + request.model->metric + ":" + weights);
  }
  std::sort(items.begin(), items.end());
  std::string settings;
  for (const std::string& item : items) settings += (settings.empty() ? "" : " ") + item;
  return settings.empty() ? "defaults" : settings;
}

std::string settings_difference(const std::string& recorded, const std::string& current,
                                const std::string& file) {
  auto before = settings_items(recorded);
  const auto now = settings_items(current);
  for (const auto& [name, value] : now) before.emplace(name, "");  // every name once
  std::string out;
  for (const auto& [name, old_value] : before) {
    const auto it = now.find(name);
    const std::string new_value = it == now.end() ? "" : it->second;
    if (old_value == new_value) continue;
    out += (out.empty() ? "" : "; ") + name + ": " + (old_value.empty() ? "default" : old_value) +
           " in " + file + ", " + (new_value.empty() ? "default" : new_value) + " in this run";
  }
  return out.empty() ? "\"" + recorded + "\" in " + file + ", \"" + current + "\" now" : out;
}

LockedResults::LockedResults(const std::filesystem::path& path) : path_(path) {
  fd_ = open_for_append(path, 0);
  try {
    lock(fd_, path);
  } catch (...) {
    ::close(fd_);
    throw;
  }
  struct stat st {};
  ::fstat(fd_, &st);
  regular_ = S_ISREG(st.st_mode);
}

LockedResults::~LockedResults() {
  ::close(fd_);
  for (const int fd : replaced_) ::close(fd);
}

void LockedResults::truncate() {
  if (regular_ && ::ftruncate(fd_, 0) != 0) {
    throw InputError(path_.string() + ": cannot empty it: " + std::strerror(errno));
  }
}

void LockedResults::replace(const std::string& text) {
  // The file a symbolic link names is replaced, not the link.
  std::error_code ec;
  const std::filesystem::path target = std::filesystem::canonical(path_, ec);
  if (ec) throw InputError(path_.string() + ": cannot resolve it: " + ec.message());
  const std::filesystem::path temp = target.string() + ".qm3d-tmp-" + std::to_string(::getpid());
  const int fd = open_for_append(temp, O_EXCL | O_NOFOLLOW);
  const auto fail = [&](const std::string& what) {
    ::close(fd);
    ::unlink(temp.c_str());
    throw InputError(path_.string() + ": " + what + ": " + std::strerror(errno));
  };
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK) fail("cannot lock a copy");
  if (::write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size()) ||
      ::fsync(fd) != 0) {
    fail("cannot write a copy (disk full?)");
  }
  if (::rename(temp.c_str(), target.c_str()) != 0) fail("cannot replace it");
  // The old version stays locked: a batch that opened it before the rename must not take it.
  replaced_.push_back(fd_);
  fd_ = fd;
}

void LockedResults::write_line(const std::string& row) {
  const std::string line = row + "\n";
  std::lock_guard<std::mutex> guard(mutex_);
  const ssize_t n = ::write(fd_, line.data(), line.size());
  if (n != static_cast<ssize_t>(line.size())) {
    throw InputError(path_.string() + ": write failed (disk full?)");
  }
}

ResumeState read_resume(const std::string& text, const std::string& file,
                        const std::string& settings, bool retry_failed,
                        const std::vector<std::string>& value_names) {
  ResumeState state;
  std::istringstream in(text);
  std::string line;
  const std::vector<std::string> full = csv_split(batch_header(value_names));
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!state.has_header) {
      state.widened = check_header(line, file, value_names);
      header = csv_split(line);
      state.has_header = true;
      state.kept_text += batch_header(value_names) + "\n";
      continue;
    }
    const auto f = csv_split(line);
    if (f.size() < header.size()) continue;  // not a row (a blank line)
    if (f.back() != settings) {
      throw InputError(file + ": scored with other settings (" +
                       settings_difference(f.back(), settings, file) +
                       "): resume with the same options, or write to another -o");
    }
    if (retry_failed && row_failed(f)) {
      ++state.retried;
      continue;
    }
    state.done.emplace(f[0], f[1], f[2]);
    state.kept_text += (state.widened ? remap_row(f, header, full) : line) + "\n";
  }
  return state;
}

std::string tidy_results(const std::string& text, const std::vector<RowKey>& order,
                         const std::vector<std::string>& value_names) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line)) return text;
  const std::vector<std::string> header = csv_split(line);
  std::map<RowKey, std::size_t> rank;
  for (const RowKey& k : order) rank.emplace(k, rank.size());
  std::set<std::string> metrics;
  std::vector<std::pair<std::size_t, std::vector<std::string>>> rows;  // (rank, fields)
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    auto f = csv_split(line);
    if (f.size() < header.size()) continue;
    const auto it = rank.find({f[0], f[1], f[2]});
    rows.emplace_back(it == rank.end() ? order.size() : it->second, std::move(f));
    metrics.insert(rows.back().second[2]);
  }
  // stable: rows outside `order` keep their file order, after the others.
  std::stable_sort(rows.begin(), rows.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::set<std::string> used;
  for (const std::string& m : metrics) {
    if (const MetricSpec* spec = default_registry().find(m)) {
      used.insert(spec->value_names.begin(), spec->value_names.end());
    }
  }
  std::vector<std::string> kept;
  for (const std::string& n : value_names) {
    if (used.count(n)) kept.push_back(n);
  }
  const std::vector<std::string> to = csv_split(batch_header(kept));
  std::string out = batch_header(kept) + "\n";
  for (const auto& row : rows) out += remap_row(row.second, header, to) + "\n";
  return out;
}

std::string tidy_results(const std::string& text, const std::vector<RowKey>& order) {
  const std::vector<std::string> header = csv_split(text.substr(0, text.find('\n')));
  const std::size_t fixed = csv_split(csv_header()).size();
  // batch_header(names): the fixed columns, the names, their two directions, settings.
  if (header.size() <= fixed || header.back() != "settings" || (header.size() - fixed - 1) % 3) {
    return text;
  }
  const auto first = header.begin() + static_cast<std::ptrdiff_t>(fixed);
  const std::vector<std::string> names(
      first, first + static_cast<std::ptrdiff_t>((header.size() - fixed - 1) / 3));
  return tidy_results(text, order, names);
}

std::size_t count_error_rows(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::size_t errors = 0;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) errors += row_failed(csv_split(line)) ? 1 : 0;
  return errors;
}

}  // namespace qm3d::study
