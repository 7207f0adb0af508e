#include "qm3d/common/metric.h"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <future>
#include <locale>
#include <sstream>
#include <thread>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/ply.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/common/warning.h"

namespace qm3d {
namespace {

constexpr std::size_t kSniffBytes = 1 << 20;  // enough for any PLY / PCD header

std::string head_of(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path.string() + ": no such file");
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path.string() + ": is a directory, not a file");
  }
  // A device (/dev/zero) never ends and a FIFO without writer would block the open below.
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path.string() + ": not a regular file (" + file_kind(path) + ")");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot be opened for reading");
  std::string bytes(kSniffBytes, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw InputError(path.string() + ": read failed");
  return bytes;
}

// The first word of the first line that is not blank or a comment.
std::string first_word(const std::string& bytes, char comment) {
  std::istringstream in(bytes);
  std::string line;
  while (std::getline(in, line)) {
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == comment) continue;
    std::istringstream words(line.substr(start));
    std::string w;
    words >> w;
    return w;
  }
  return {};
}

bool is_off_keyword(const std::string& w) {
  // [ST][C][N][4][n]OFF (the Princeton OFF variants).
  if (w.size() < 3 || w.compare(w.size() - 3, 3, "OFF") != 0) return false;
  return std::all_of(w.begin(), w.end() - 3,
                     [](char c) { return std::strchr("STCN4n", c) != nullptr; });
}

bool has_line_starting(const std::string& text, const char* keyword) {
  const std::size_t n = std::strlen(keyword);
  std::size_t pos = 0;
  while (pos < text.size()) {
    const auto start = text.find_first_not_of(" \t", pos);
    if (start != std::string::npos && text.compare(start, n, keyword) == 0) return true;
    const auto next = text.find('\n', pos);
    if (next == std::string::npos) break;
    pos = next + 1;
  }
  return false;
}

bool off_has_faces(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  bool keyword = false;
  while (std::getline(in, line)) {
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream words(line.substr(start));
    if (!keyword) {
      std::string w;
      words >> w;
      keyword = true;
      long long v = 0, f = 0;
      if (words >> v >> f) return f > 0;  // counts on the keyword's line
      continue;
    }
    long long v = 0, f = 0;
    if (words >> v >> f) return f > 0;
    return true;  // malformed counts: let the mesh reader say what is wrong
  }
  return true;
}

}  // namespace

FileFormat detect_format(const std::string& bytes, const std::string& name) {
  if (bytes.compare(0, 3, "ply") == 0 && bytes.size() > 3 &&
      (bytes[3] == '\n' || bytes[3] == '\r')) {
    return FileFormat::kPly;
  }
  const std::string pcd_first = first_word(bytes, '#');
  if (bytes.compare(0, 6, "# .PCD") == 0 || pcd_first == "VERSION" || pcd_first == "FIELDS") {
    return FileFormat::kPcd;
  }
  if (is_off_keyword(first_word(bytes, '#'))) return FileFormat::kOff;
  if (bytes.find('\0') == std::string::npos && has_line_starting(bytes, "v ")) {
    return FileFormat::kObj;
  }
  throw FormatError(name + ": not a PLY, OBJ, OFF or PCD file (unrecognised content)");
}

namespace {

// The format a file's content shows, else the one its extension names (so that a damaged file
// gets its format's precise error), else FormatError.
FileFormat format_of_file(const std::string& head, const std::filesystem::path& path) {
  try {
    return detect_format(head, path.string());
  } catch (const FormatError&) {
    const std::string ext = lower_extension(path);
    if (ext == "ply") return FileFormat::kPly;
    if (ext == "obj") return FileFormat::kObj;
    if (ext == "off") return FileFormat::kOff;
    if (ext == "pcd") return FileFormat::kPcd;
    throw FormatError(path.string() + ": unknown format '" + path.extension().string() +
                      "' (the content is not PLY, OBJ, OFF or PCD)");
  }
}

}  // namespace

FileFormat detect_format(const std::filesystem::path& path) {
  return format_of_file(head_of(path), path);
}

// ---------------------------------------------------------------------------------------------
// Input

namespace {

// A pipe's content (`<(zcat a.ply.gz)`, a FIFO) copied into an anonymous in-memory file: the
// readers look at a file more than once (its head, then all of it) and a pipe gives its bytes
// only once.
class PipeSpool {
 public:
  explicit PipeSpool(const std::filesystem::path& pipe) {
    const std::string bytes = read_file_bytes(pipe);
    fd_ = ::memfd_create("qm3d-pipe", MFD_CLOEXEC);
    if (fd_ < 0) throw InputError(pipe.string() + ": cannot hold the pipe's content in memory");
    for (std::size_t done = 0; done < bytes.size();) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw InputError(pipe.string() + ": cannot hold the pipe's content in memory");
      done += static_cast<std::size_t>(n);
    }
  }
  PipeSpool(const PipeSpool&) = delete;
  PipeSpool& operator=(const PipeSpool&) = delete;
  ~PipeSpool() { ::close(fd_); }
  std::filesystem::path path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_ = -1;
};

bool is_pipe(const std::filesystem::path& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (auto p = text.find(from); p != std::string::npos; p = text.find(from, p + to.size())) {
    text.replace(p, from.size(), to);
  }
  return text;
}

// Runs a reader of a spooled pipe; its errors and warnings name the pipe, not the in-memory copy.
template <class Read>
auto read_renamed(const std::filesystem::path& read_path, const std::string& name, Read read) {
  try {
    auto data = read();
    if (read_path.string() != name) {
      for (std::string& w : data.warnings) w = replaced(w, read_path.string(), name);
    }
    return data;
  } catch (const InputError& e) {
    throw InputError(replaced(e.what(), read_path.string(), name));
  } catch (const FormatError& e) {
    throw FormatError(replaced(e.what(), read_path.string(), name));
  } catch (const NumericError& e) {
    throw NumericError(replaced(e.what(), read_path.string(), name));
  }
}

}  // namespace

struct Input::State {
  std::string name;
  std::shared_ptr<PipeSpool> spool;  ///< a pipe's content; `path` is then its in-memory copy
  std::filesystem::path path;
  FileFormat format = FileFormat::kPly;
  Kind kind = Kind::kCloud;
  Readers readers;
  ReadOptions read_options;
  std::mutex mutex;
  std::optional<MeshData> mesh;
  std::optional<CloudData> cloud;
};

Input Input::from_file(const std::filesystem::path& path, const Registry& registry,
                       const ReadOptions& options) {
  Input in;
  in.state_ = std::make_shared<State>();
  State& s = *in.state_;
  s.name = path.string();
  s.path = path;
  if (is_pipe(path)) {
    s.spool = std::make_shared<PipeSpool>(path);
    s.path = s.spool->path();
  }
  s.readers = registry.readers();
  s.read_options = options;
  const std::string head = head_of(s.path);
  s.format = format_of_file(head, path);
  switch (s.format) {
    case FileFormat::kPly: {
      // The declared counts are checked against the whole file's size (the head may be cut).
      const ply::Header h = ply::parse_header(head, s.name, std::filesystem::file_size(s.path));
      s.kind = Kind::kCloud;
      for (const auto& e : h.elements) {
        if (e.name == "face" && e.count > 0) s.kind = Kind::kMesh;
      }
      break;
    }
    case FileFormat::kPcd: s.kind = Kind::kCloud; break;
    case FileFormat::kOff: s.kind = off_has_faces(head) ? Kind::kMesh : Kind::kCloud; break;
    case FileFormat::kObj: {
      // Faces may come after many vertices: look at the whole text.
      const std::string text = head.size() < kSniffBytes ? head : read_file_bytes(s.path);
      s.kind = has_line_starting(text, "f ") || has_line_starting(text, "f\t") ? Kind::kMesh
                                                                               : Kind::kCloud;
      break;
    }
  }
  return in;
}

Input Input::from_mesh(ColoredMesh mesh, std::string name, bool has_colors) {
  return from_mesh(MeshData{std::move(mesh), has_colors, {}}, std::move(name));
}

Input Input::from_mesh(MeshData mesh, std::string name) {
  Input in;
  in.state_ = std::make_shared<State>();
  in.state_->name = std::move(name);
  in.state_->kind = Kind::kMesh;
  in.state_->mesh = std::move(mesh);
  return in;
}

Input Input::from_cloud(ColoredCloud cloud, std::string name) {
  Input in;
  in.state_ = std::make_shared<State>();
  in.state_->name = std::move(name);
  in.state_->kind = Kind::kCloud;
  in.state_->cloud = CloudData{std::move(cloud), {}, {}};
  return in;
}

const std::string& Input::name() const { return state_->name; }
const std::filesystem::path& Input::path() const { return state_->path; }
Input::Kind Input::kind() const { return state_->kind; }
FileFormat Input::format() const { return state_->format; }

const MeshData& Input::mesh() const {
  State& s = *state_;
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.mesh) return *s.mesh;
  // A cloud in a mesh format still goes to the mesh reader, whose error says what is missing.
  if (s.kind != Kind::kMesh && (s.path.empty() || s.format == FileFormat::kPcd)) {
    throw FormatError(s.name + ": a point cloud (no faces), not a mesh; score it with PCQM");
  }
  if (!s.readers.mesh) throw std::logic_error("no mesh reader registered");
  s.mesh = read_renamed(s.path, s.name,
                        [&] { return s.readers.mesh(s.path, s.format, s.read_options); });
  return *s.mesh;
}

const ColoredCloud& Input::cloud() const {
  State& s = *state_;
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.cloud) return s.cloud->cloud;
  if (s.path.empty()) {  // a mesh in memory: its vertices
    s.cloud = CloudData{vertex_cloud(s.mesh->mesh), {}, {}};
    if (!s.mesh->has_colors) s.cloud->cloud.colors.clear();
    return s.cloud->cloud;
  }
  const bool mesh_format = s.format == FileFormat::kObj || s.format == FileFormat::kOff;
  const auto& read = mesh_format ? s.readers.mesh_vertices : s.readers.cloud;
  if (!read) throw std::logic_error("no cloud reader registered");
  s.cloud = read_renamed(s.path, s.name, [&] { return read(s.path, s.format, s.read_options); });
  return s.cloud->cloud;
}

const ReadOptions& Input::read_options() const { return state_->read_options; }

std::vector<std::string> Input::cloud_warnings() const {
  cloud();
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->cloud->warnings;
}

const std::vector<Vec3>& Input::cloud_normals() const {
  cloud();
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->cloud->normals;
}

void Input::load(Kind as) const {
  if (as == Kind::kMesh) {
    mesh();
  } else {
    cloud();
  }
}

void Input::release() const {
  State& s = *state_;
  std::lock_guard<std::mutex> lock(s.mutex);
  if (s.path.empty()) return;  // data in memory cannot be read again
  s.mesh.reset();
  s.cloud.reset();
}

// ---------------------------------------------------------------------------------------------
// Metric specs and the registry

std::vector<std::string> csv_value_names(const std::vector<const MetricSpec*>& specs) {
  std::vector<std::string> names;
  for (const MetricSpec* spec : specs) {
    for (const std::string& n : spec->value_names) {
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
  }
  return names;
}

std::optional<bool> MetricSpec::column_higher_is_better(const std::string& column) const {
  std::string name = column;
  for (const char* prefix : {"dist_to_ref_", "ref_to_dist_"}) {
    if (name.rfind(prefix, 0) == 0) name.erase(0, std::strlen(prefix));
  }
  if (name == "score") return higher_is_better;
  if (std::find(value_names.begin(), value_names.end(), name) == value_names.end()) {
    return std::nullopt;
  }
  return std::find(quality_value_names.begin(), quality_value_names.end(), name) !=
         quality_value_names.end();
}

bool MetricSpec::applies(const Input& reference, const Input& distorted) const {
  switch (applies_to) {
    case AppliesTo::kMeshes: return reference.is_mesh() && distorted.is_mesh();
    case AppliesTo::kClouds: return !reference.is_mesh() && !distorted.is_mesh();
    case AppliesTo::kBoth: return true;
  }
  return false;
}

Input::Kind MetricSpec::reads_for(const Input& reference, const Input& distorted) const {
  if (reads_two_meshes_as_meshes && reference.is_mesh() && distorted.is_mesh()) {
    return Input::Kind::kMesh;
  }
  return reads;
}

bool MetricSpec::per_element_on_inputs(const Input& reference, const Input& distorted) const {
  return per_element_on_input &&
         !(two_meshes_scored_on_samples && reference.is_mesh() && distorted.is_mesh());
}

Input::Kind MetricSpec::reads_input(const Input& input, const Input& reference,
                                    const Input& distorted) const {
  if (reads_each_as_is) return input.kind();
  return reads_for(reference, distorted);
}

namespace {

std::string value_text(const nlohmann::json& v) { return v.dump(); }

// A bound as written in messages: 5, not 5.0.
std::string bound_text(double x) {
  constexpr double kExactIntegers = 9e15;
  if (std::floor(x) == x && std::abs(x) < kExactIntegers) {
    return std::to_string(static_cast<long long>(x));
  }
  return nlohmann::json(x).dump();
}

void check_value(const MetricSpec& spec, const OptionSpec& o, const nlohmann::json& v) {
  const auto bad = [&](const std::string& why) {
    throw std::invalid_argument(spec.name + ": option '" + o.name + "' " + why + " (got " +
                                value_text(v) + ")");
  };
  const nlohmann::json& d = o.default_value;
  const auto check_number = [&](const nlohmann::json& x) {
    if (!x.is_number()) bad("must be a number");
    const double n = x.get<double>();
    if (!std::isfinite(n)) bad("must be finite");
    if (n < o.min || (o.min_exclusive && n == o.min)) {
      bad(std::string("must be ") + (o.min_exclusive ? "> " : ">= ") + bound_text(o.min));
    }
    if (n > o.max) bad("must be <= " + bound_text(o.max));
  };
  if (d.is_boolean()) {
    if (!v.is_boolean()) bad("must be true or false");
  } else if (d.is_number_integer()) {
    if (!v.is_number_integer()) bad("must be an integer");
    check_number(v);
  } else if (d.is_number()) {
    check_number(v);
  } else if (d.is_string()) {
    if (!v.is_string()) bad("must be a string");
    if (!o.choices.empty() &&
        std::find(o.choices.begin(), o.choices.end(), v.get<std::string>()) == o.choices.end()) {
      std::string list;
      for (const auto& c : o.choices) list += (list.empty() ? "" : ", ") + c;
      bad("must be one of " + list);
    }
  } else if (d.is_array()) {
    if (!v.is_array() || v.size() != d.size()) {
      bad("must be a list of " + std::to_string(d.size()) + " numbers");
    }
    for (const auto& x : v) check_number(x);
  }
}

}  // namespace

OptionValues MetricSpec::complete(const OptionValues& given) const {
  if (!given.is_null() && !given.is_object()) {
    throw std::invalid_argument(name + ": options must be a JSON object");
  }
  OptionValues out = nlohmann::json::object();
  for (const auto& o : options) out[o.name] = o.default_value;
  if (given.is_object()) {
    for (const auto& item : given.items()) {
      // Not a structured binding: C++17 lambdas cannot capture those (clang rejects it).
      const std::string& key = item.key();
      const nlohmann::json& value = item.value();
      const auto it = std::find_if(options.begin(), options.end(),
                                   [&](const OptionSpec& o) { return o.name == key; });
      if (it == options.end()) {
        std::string known;
        for (const auto& o : options) known += (known.empty() ? "" : ", ") + o.name;
        throw std::invalid_argument(name + ": unknown option '" + key + "' (" +
                                    (known.empty() ? "it takes none" : "known: " + known) + ")");
      }
      check_value(*this, *it, value);
      out[key] = value;
    }
  }
  return out;
}

void Registry::add(MetricSpec spec) {
  if (find(spec.name)) throw std::logic_error("metric '" + spec.name + "' registered twice");
  metrics_.push_back(std::move(spec));
}

const MetricSpec* Registry::find(const std::string& name) const {
  for (const auto& m : metrics_) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

const MetricSpec& Registry::get(const std::string& name) const {
  if (const MetricSpec* m = find(name)) return *m;
  std::string known;
  for (const auto& m : metrics_) known += (known.empty() ? "" : ", ") + m.name;
  throw FormatError("unknown metric '" + name + "' (expected " + known + ")");
}

std::optional<std::pair<bool, std::string>> Registry::column_orientation(
    const std::string& column) const {
  if (const MetricSpec* spec = find(column)) {
    return std::make_pair(spec->higher_is_better, "registered metric " + spec->name);
  }
  if (column == "score") return std::nullopt;  // every metric's: says nothing alone
  for (const MetricSpec& spec : metrics_) {
    if (const auto h = spec.column_higher_is_better(column)) {
      return std::make_pair(*h, "named value of " + spec.name);
    }
  }
  return std::nullopt;
}

std::vector<const MetricSpec*> Registry::applicable(const Input& reference,
                                                    const Input& distorted) const {
  std::vector<const MetricSpec*> out;
  for (const auto& m : metrics_) {
    if (m.in_compare && m.applies(reference, distorted)) out.push_back(&m);
  }
  return out;
}

const MetricSpec& Registry::auto_metric(const Input& reference, const Input& distorted) const {
  const auto all = applicable(reference, distorted);
  if (all.empty()) {
    throw FormatError("no metric applies to " + reference.name() + " and " + distorted.name());
  }
  return *all.front();
}

const SurfaceSampler& Registry::sampler() const {
  if (!sampler_) throw std::logic_error("no surface sampler registered (mesh module)");
  return sampler_;
}

OptionValues options_for(const MetricSpec& spec, const OptionValues& all) {
  OptionValues out = nlohmann::json::object();
  if (!all.is_object()) return out;
  for (const auto& o : spec.options) {
    if (all.contains(o.name)) out[o.name] = all[o.name];
  }
  return out;
}

namespace {

// Both inputs' cloud reader warnings, each line once (the same file may be both).
/// The cloud readers' warnings of the inputs read as clouds (once each).
std::vector<std::string> cloud_reader_warnings(const Input& reference, bool reference_is_cloud,
                                               const Input& distorted, bool distorted_is_cloud) {
  std::vector<std::string> all;
  if (reference_is_cloud) all = reference.cloud_warnings();
  if (!distorted_is_cloud) return all;
  for (std::string& w : distorted.cloud_warnings()) {
    if (std::find(all.begin(), all.end(), w) == all.end()) all.push_back(std::move(w));
  }
  return all;
}

}  // namespace

int max_threads() {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  return std::max(kMinThreadLimit, static_cast<int>(std::min(cores, 1u << 20)) * kThreadsPerCore);
}

void check_thread_count(int threads) {
  if (threads < 0) throw std::invalid_argument("threads: must be 0 (all cores) or more");
  if (threads > max_threads()) {
    throw std::invalid_argument("threads: " + std::to_string(threads) + " is more than the " +
                                std::to_string(max_threads()) + " qm3d runs on this machine (" +
                                std::to_string(kThreadsPerCore) + " per core, at least " +
                                std::to_string(kMinThreadLimit) + "; 0 = all cores)");
  }
}

void check_coordinate_range(const std::vector<Vec3>& positions, const std::string& name) {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  bool any = false;
  for (const Vec3& p : positions) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    for (int k = 0; k < 3; ++k) {
      lo[k] = any ? std::min(lo[k], p[k]) : p[k];
      hi[k] = any ? std::max(hi[k], p[k]) : p[k];
    }
    any = true;
  }
  if (!any) return;
  double largest = 0, side = 0;
  for (int k = 0; k < 3; ++k) {
    largest = std::max({largest, std::abs(lo[k]), std::abs(hi[k])});
    side = std::max(side, hi[k] - lo[k]);
  }
  if (largest > kMaxCoordinate) {
    throw NumericError(name + ": coordinates up to " + short_number(largest) +
                       " are too large: squared distances would overflow (the metrics need "
                       "|x|, |y|, |z| <= " +
                       short_number(kMaxCoordinate) + "; rescale the data)");
  }
  if (side > 0 && side < kMinBoxSide) {
    throw NumericError(name + ": the bounding box's longest side is " + short_number(side) +
                       ", too small: squared distances would underflow (the metrics need at "
                       "least " +
                       short_number(kMinBoxSide) + "; rescale the data)");
  }
}

namespace {

void check_model(const RunOptions& run) {
  if (!run.model) return;
  for (std::size_t k = 0; k < run.model->weights.size(); ++k) {
    if (!std::isfinite(run.model->weights[k])) {
      throw std::invalid_argument("weights: weight " + std::to_string(k + 1) + " of " +
                                  std::to_string(run.model->weights.size()) + " is " +
                                  short_number(run.model->weights[k]) + " (must be finite)");
    }
  }
}

const std::vector<Vec3>& positions_of(const Input& in, Input::Kind as) {
  return as == Input::Kind::kMesh ? in.mesh().mesh.positions : in.cloud().positions;
}

// The first non-finite pooled feature of a direction, as "f3 nan"; empty when all are finite.
std::string non_finite_feature(const DirectionResult& d, const std::vector<std::string>& names) {
  for (std::size_t k = 0; k < d.features.size(); ++k) {
    if (std::isfinite(d.features[k])) continue;
    const std::string feature = k < names.size() ? names[k] : "feature " + std::to_string(k + 1);
    return feature + " " + short_number(d.features[k]);
  }
  return {};
}

// A metric never reports a non-finite score as a result: NumericError naming the metric, the
// direction, the value and the first non-finite feature. A non-finite feature the score does not
// use (weight 0: the pooling skips it, as the reference tools do) is a warning, not an error, so
// that such scores stay the reference's.
// A quality (higher is better) may be +inf: the PSNR of identical inputs. NaN never passes, in a
// score or a named value.
bool acceptable_score(const MetricSpec& spec, double v) {
  return std::isfinite(v) || (spec.higher_is_better && v == HUGE_VAL);
}

void check_named_values(const MetricSpec& spec, const NamedValues& values, const std::string& where) {
  for (const auto& [name, v] : values) {
    if (std::isnan(v)) {
      throw NumericError(spec.title + ": " + where + name + " is not a number (degenerate data)");
    }
  }
}

void check_finite_result(const MetricSpec& spec, MetricResult& r) {
  check_named_values(spec, r.values, "");
  const auto check = [&](const std::optional<DirectionResult>& d, Direction which) {
    if (!d) return;
    check_named_values(spec, d->values, "the " + direction_name(which) + " value ");
    const std::string feature = non_finite_feature(*d, r.feature_names);
    if (!acceptable_score(spec, d->score)) {
      throw NumericError(spec.title + ": the " + direction_name(which) + " score " +
                         short_number(d->score) + " is not finite" +
                         (feature.empty() ? "" : " (" + feature + ")") +
                         " (degenerate data or options: e.g. a radius so small that no "
                         "neighbour is within it)");
    }
    if (!feature.empty() && !r.feature_names.empty()) {
      r.warnings.push_back(spec.title + ": the " + direction_name(which) + " feature " + feature +
                           " is not finite; the score does not use it (weight 0)");
    }
  };
  check(r.dist_to_ref, Direction::kDistToRef);
  check(r.ref_to_dist, Direction::kRefToDist);
  if (!acceptable_score(spec, r.score)) {
    throw NumericError(spec.title + ": the score " + short_number(r.score) + " is not finite");
  }
}

}  // namespace

MetricResult run_metric(const MetricSpec& spec, const Input& reference, const Input& distorted,
                        const RunOptions& run, const OptionValues& options) {
  const auto start = std::chrono::steady_clock::now();
  const OptionValues values = spec.complete(options);
  if (run.model && !spec.takes_model) {
    throw std::invalid_argument(spec.name + " has no linear model: --weights / --model do not apply");
  }
  check_thread_count(run.threads);
  check_model(run);
  // Both inputs are read concurrently unless one thread was asked for.
  const Input::Kind ref_reads = spec.reads_input(reference, reference, distorted);
  const Input::Kind dist_reads = spec.reads_input(distorted, reference, distorted);
  // A metric that reads its files itself gets them unread (it checks them).
  if (!spec.reads_files) {
    auto ref_task = std::async(run.threads == 1 ? std::launch::deferred : std::launch::async,
                               [&] { reference.load(ref_reads); });
    distorted.load(dist_reads);
    ref_task.get();
  }
  // Taken now: the metric may release the inputs (RunOptions::inputs_done).
  const std::vector<std::string> reading =
      spec.reads_files ? std::vector<std::string>{}
                       : cloud_reader_warnings(reference, ref_reads == Input::Kind::kCloud,
                                               distorted, dist_reads == Input::Kind::kCloud);
  MetricResult result;
  try {
    if (!spec.reads_files) {
      check_coordinate_range(positions_of(reference, ref_reads), reference.name());
      check_coordinate_range(positions_of(distorted, dist_reads), distorted.name());
    }
    result = spec.run(spec, reference, distorted, run, values);
    check_finite_result(spec, result);
  } catch (const NumericError& e) {
    throw NumericError(e.what() + std::string(" (reference ") + reference.name() +
                       ", distorted " + distorted.name() + ")");
  }
  result.warnings.insert(result.warnings.begin(), reading.begin(), reading.end());
  fit_warnings(result, {reference.name(), distorted.name()});
  result.provenance.version = kVersion;
  // A metric that follows one of several tools by input kind names the one it followed.
  if (result.provenance.reproduces.empty()) result.provenance.reproduces = spec.reproduces;
  result.provenance.reference = reference.name();
  result.provenance.distorted = distorted.name();
  result.provenance.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace qm3d
