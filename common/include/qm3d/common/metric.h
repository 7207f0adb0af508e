// One way to run any metric: inputs recognised by content, a registry of metrics with their own
// options, and run_metric().
//
// The metric modules register what they bring (qm3d/mesh/metrics.h, qm3d/pointcloud/metrics.h):
// their metrics, and the readers and the surface sampler an Input uses. A program builds one
// Registry, registers the modules it links, and runs metrics by name:
//
//   qm3d::Registry registry;
//   qm3d::mesh::register_metrics(registry);
//   qm3d::pointcloud::register_metrics(registry);
//   const qm3d::Input ref = registry.read("ref.ply"), dist = registry.read("dist.ply");
//   const qm3d::MetricSpec& spec = registry.auto_metric(ref, dist);   // CMDM for meshes, ...
//   qm3d::RunOptions run;  run.threads = 2;
//   qm3d::MetricResult r = qm3d::run_metric(spec, ref, dist, run, {{"scales", 3}});
//
// Adding a metric: one file in its module with its compute function and a MetricSpec, and one
// line in the module's register_metrics(). The tool (commands, options, --help, batch, compare)
// learns it from the registry.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "qm3d/common/color.h"
#include "qm3d/common/grid_samples.h"
#include "qm3d/common/reading.h"
#include "qm3d/common/result.h"
#include "qm3d/common/types.h"

namespace qm3d {

/// File formats recognised by content (their first bytes), whatever the extension.
enum class FileFormat { kPly, kObj, kOff, kPcd };

/// The format of a file's content: "ply" magic, an OFF keyword (OFF, COFF, NOFF, ...), a PCD
/// header line, else OBJ when the text has vertex lines. Content that is none of them falls back
/// to the extension (.ply, .obj, .off, .pcd: that reader then says what is wrong); FormatError
/// naming the file otherwise.
FileFormat detect_format(const std::filesystem::path& path);
/// The same on content already read (`name` for messages).
FileFormat detect_format(const std::string& bytes, const std::string& name);

/// A mesh as read from a file: vertices (with their colours, when the file has them), triangles
/// (polygons fan-triangulated, unused vertices dropped) and the reader's repairs.
struct MeshData {
  ColoredMesh mesh;
  bool has_colors = true;
  std::vector<std::string> warnings;
};

class Registry;

/// One object to score: a file (read on first use, then kept) or data already in memory.
/// Meshes are recognised by content: a PLY with faces, an OBJ with faces, any OFF; clouds are
/// PLY without faces and PCD. Any mesh can be used as a cloud (its vertices). Thread-safe.
class Input {
 public:
  enum class Kind { kMesh, kCloud };

  /// A file; its kind is recognised now (from its header), its content read when first used
  /// (as `options` say: the scale of float colours).
  static Input from_file(const std::filesystem::path& path, const Registry& registry,
                         const ReadOptions& options = {});
  /// A mesh in memory (`name` appears in results and messages).
  static Input from_mesh(ColoredMesh mesh, std::string name, bool has_colors = true);
  /// A mesh in memory with its reader's warnings (e.g. mesh/mesh_io.h mesh_from_arrays).
  static Input from_mesh(MeshData mesh, std::string name);
  /// A cloud in memory.
  static Input from_cloud(ColoredCloud cloud, std::string name);

  const std::string& name() const;
  /// The file, or empty for data in memory.
  const std::filesystem::path& path() const;
  Kind kind() const;
  bool is_mesh() const { return kind() == Kind::kMesh; }
  FileFormat format() const;  ///< the file's format (kPly for data in memory)
  /// How the file is read (defaults for data in memory): colour scale, texture map override.
  const ReadOptions& read_options() const;

  /// The mesh. FormatError naming the input when it is a cloud.
  const MeshData& mesh() const;
  /// The cloud: a cloud's points, or a mesh's vertices (every vertex of the file, colours
  /// required).
  const ColoredCloud& cloud() const;
  /// What the reader of cloud() warned of (empty for data in memory); reads the cloud.
  std::vector<std::string> cloud_warnings() const;
  /// The normals the cloud's file holds (PLY nx, ny, nz), one per point of cloud(), as stored;
  /// empty when it has none (and for data in memory). Reads the cloud.
  const std::vector<Vec3>& cloud_normals() const;
  /// Reads now what `kind` needs (so that two inputs can be read concurrently).
  void load(Kind as) const;
  /// Frees what was read from the file (it is read again if used later); data given in memory
  /// is kept. References from mesh() / cloud() are invalid afterwards: call it only when no one
  /// uses them (e.g. from RunOptions::inputs_done).
  void release() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

/// What the modules register to read inputs (with the reader's warnings).
struct Readers {
  /// A mesh file (OBJ, OFF, PLY) of the given format; colours kept when present.
  std::function<MeshData(const std::filesystem::path&, FileFormat, const ReadOptions&)> mesh;
  /// Every vertex of a mesh file (OBJ, OFF) as a cloud.
  std::function<CloudData(const std::filesystem::path&, FileFormat, const ReadOptions&)>
      mesh_vertices;
  /// A cloud file (PLY, PCD); a PLY mesh gives its vertices.
  std::function<CloudData(const std::filesystem::path&, FileFormat, const ReadOptions&)> cloud;
};

/// How a surface is sampled into a cloud (mesh/sampling.h): `points` samples, or `density` per
/// unit area when points is 0; one seed gives the same cloud everywhere.
struct SurfaceSampling {
  std::size_t points = 0;
  double density = 0;
  std::uint64_t seed = 1;
};
/// Samples an input's surface (textured OBJ files from their texture).
using SurfaceSampler = std::function<ColoredCloud(const Input&, const SurfaceSampling&)>;
/// Samples a mesh input on a grid as MPEG mmetric does (mesh/grid_sampling.h; textured OBJ
/// files from their texture); FormatError naming the input when it is not a mesh.
using GridSampler = std::function<GridSamples(const Input&, const GridSamplingOptions&)>;

/// Each vertex of one mesh with its correspondence on another mesh's surface, as colours in
/// LAB2000HL: `own[v]` the vertex's, `matched[v]` the one at its closest point on the other
/// surface (CMDM's projection and interpolation of the face's vertex colours). One entry per
/// vertex of the iterated input's mesh (MeshData::mesh).
struct SurfaceColours {
  std::vector<Lab> own;
  std::vector<Lab> matched;
  std::vector<std::string> warnings;  ///< the other mesh's repairs (e.g. faces dropped)
};
/// Matches `iterated`'s vertices on `other`'s surface (both meshes with vertex colours; a
/// FormatError naming the file otherwise), with `threads` OpenMP threads (0 = the default): the
/// same values for any count.
using SurfaceColourMatcher = std::function<SurfaceColours(
    const Input& iterated, const Input& other, const Lab2000hlTable& table, int threads)>;

/// One option of a metric: its name (as the tool's --name and the bindings' keyword), help text
/// and default. The default's JSON type is the option's type: integer, number, boolean (a
/// flag), string (one of `choices` when not empty) or an array of numbers (its length fixed).
struct OptionSpec {
  std::string name;
  std::string help;
  nlohmann::json default_value;
  std::vector<std::string> choices;
  double min = -1e300;       ///< inclusive bounds of a number
  double max = 1e300;
  bool min_exclusive = false;  ///< min itself is not allowed (e.g. a radius > 0)
};

/// Which inputs a metric scores.
enum class AppliesTo { kMeshes, kClouds, kBoth };

/// The option values of one metric run: a JSON object {name: value}; missing names take their
/// defaults.
using OptionValues = nlohmann::json;

struct MetricSpec;
/// Computes the metric on two inputs. `options` holds every option of the spec (defaults filled
/// and checked by run_metric).
using MetricRunner = std::function<MetricResult(const MetricSpec&, const Input& reference,
                                                const Input& distorted, const RunOptions&,
                                                const OptionValues& options)>;

struct MetricSpec {
  std::string name;     ///< "cmdm": the command, the batch list's metric, the result's metric
  std::string title;    ///< "CMDM": how the tool prints it
  std::string summary;  ///< one line for --help
  /// The reference implementation whose numbers the metric reproduces, by repository and
  /// commit or version ("MEPP-team/MEPP2 @ d977d05"); empty when it has none (a definition of
  /// qm3d's own). Echoed by --version and in every result's JSON.
  std::string reproduces;
  /// The score is a quality (PSNR: higher is better; +inf for identical inputs), not a
  /// distortion (0 = identical, higher is worse).
  bool higher_is_better = false;
  AppliesTo applies_to = AppliesTo::kBoth;
  /// How the metric reads its inputs: as meshes (faces used) or as clouds (any mesh's vertices).
  Input::Kind reads = Input::Kind::kCloud;
  /// With reads = kCloud: a pair of two meshes is read as meshes (the metric dispatches on the
  /// pair, as D_LAB does: CMDM's projection for two meshes, PCQM's nearest neighbour otherwise).
  bool reads_two_meshes_as_meshes = false;
  /// Each input is read as what it is, a mesh as a mesh and a cloud as a cloud, also in a mixed
  /// pair (ibsm renders each as it is). With it, reads_for says kMesh for two meshes only.
  bool reads_each_as_is = false;
  /// Run by `compare` (and `report`, `demo`, batch's compare rows) when it applies; false: only
  /// when asked for by name (ibsm: seconds of rendering per pair, a different family of metric).
  bool in_compare = true;
  /// How `input` is read: as reads_for(pair), or its own kind when reads_each_as_is.
  Input::Kind reads_input(const Input& input, const Input& reference,
                          const Input& distorted) const;
  Direction default_direction = Direction::kSymmetric;
  std::string direction_help;  ///< what the directions mean for this metric
  /// How the symmetric score is made of the two directions' (as the report says it).
  std::string symmetric_rule = "mean";
  bool takes_model = false;    ///< a linear model of f1..f8 (--weights / --model) applies
  /// The metric a model file must name to apply here (empty = `name`; pcqm_sampled takes PCQM
  /// models).
  std::string model_metric;
  /// The per-element values are on the input's elements (vertices or points), so that they can
  /// be written on its geometry; false when they are on something else (samples).
  bool per_element_on_input = true;
  /// With per_element_on_input false: each per-element value has a position
  /// (DirectionResult::element_positions, GeodesicPSIM's keypoints), so that maps write them as
  /// points.
  bool per_element_positions = false;
  /// The metric reads its input files itself (GeodesicPSIM: an OBJ and its texture as its
  /// reference reads them): run_metric does not load them (no second copy in memory).
  bool reads_files = false;
  /// With reads_two_meshes_as_meshes: two meshes are scored on samples of their surfaces (psnr's
  /// grid samples), so their per-element values are not on the meshes' vertices.
  bool two_meshes_scored_on_samples = false;
  /// Whether this pair's per-element values are on its inputs' elements (a map or a report
  /// layer can be drawn on them): per_element_on_input, but not for two meshes scored on
  /// samples.
  bool per_element_on_inputs(const Input& reference, const Input& distorted) const;

  const std::string& model_name() const { return model_metric.empty() ? name : model_metric; }
  std::vector<OptionSpec> options;
  MetricRunner run;
  /// The names of the values the metric reports by name (MetricResult::values and each
  /// DirectionResult::values: their CSV columns), in order; empty for f1..f8 metrics.
  std::vector<std::string> value_names;
  /// The values among value_names that are qualities (higher is better, like a PSNR); the
  /// others are distortions (an MSE, a Hausdorff distance).
  std::vector<std::string> quality_value_names;

  /// Whether a higher number in this result column is better: "score" and
  /// "dist_to_ref_score" / "ref_to_dist_score" by higher_is_better, a named value (bare or with a
  /// direction prefix) by quality_value_names; nullopt for any other column (f1..f8, seconds).
  std::optional<bool> column_higher_is_better(const std::string& column) const;
  /// True when the metric scores this pair of inputs.
  bool applies(const Input& reference, const Input& distorted) const;
  /// How the metric reads this pair: `reads`, or kMesh for two meshes when
  /// reads_two_meshes_as_meshes.
  Input::Kind reads_for(const Input& reference, const Input& distorted) const;
  /// The option values with every default filled in; std::invalid_argument naming the option
  /// for an unknown name, a wrong type, a value out of range or not among the choices.
  OptionValues complete(const OptionValues& given) const;
};

/// The metrics and readers a program knows.
class Registry {
 public:
  /// Adds a metric; std::logic_error when the name is taken.
  void add(MetricSpec spec);
  /// The metric of that name, or nullptr.
  const MetricSpec* find(const std::string& name) const;
  /// The metric of that name; FormatError listing the known names otherwise.
  const MetricSpec& get(const std::string& name) const;
  /// Every metric, in registration order.
  const std::vector<MetricSpec>& metrics() const { return metrics_; }
  /// The metrics that apply to the pair and run in `compare` (MetricSpec::in_compare), in
  /// registration order.
  std::vector<const MetricSpec*> applicable(const Input& reference, const Input& distorted) const;
  /// Whether a higher number in a score column named `column` is better, and why: a column
  /// named after a registered metric ("psnr": true) or after one of a metric's named values
  /// ("d1_mse": false, "dist_to_ref_c0_psnr": true); nullopt for other names.
  std::optional<std::pair<bool, std::string>> column_orientation(const std::string& column) const;
  /// The first metric that applies (registration order: CMDM for two meshes, PCQM otherwise).
  const MetricSpec& auto_metric(const Input& reference, const Input& distorted) const;

  Readers& readers() { return readers_; }
  const Readers& readers() const { return readers_; }
  void set_sampler(SurfaceSampler sampler) { sampler_ = std::move(sampler); }
  bool has_sampler() const { return static_cast<bool>(sampler_); }
  /// The surface sampler; std::logic_error when no module registered one.
  const SurfaceSampler& sampler() const;
  /// The mesh module's grid sampler (mmetric's); empty when no module registered one.
  void set_grid_sampler(GridSampler sampler) { grid_sampler_ = std::move(sampler); }
  const GridSampler& grid_sampler() const { return grid_sampler_; }
  /// The mesh module's closest-point colour correspondence (D_LAB's mesh side); empty when no
  /// module registered one.
  void set_colour_matcher(SurfaceColourMatcher matcher) { colour_matcher_ = std::move(matcher); }
  const SurfaceColourMatcher& colour_matcher() const { return colour_matcher_; }

  /// Input::from_file(path, *this, options).
  Input read(const std::filesystem::path& path, const ReadOptions& options = {}) const {
    return Input::from_file(path, *this, options);
  }

 private:
  std::vector<MetricSpec> metrics_;
  Readers readers_;
  SurfaceSampler sampler_;
  GridSampler grid_sampler_;
  SurfaceColourMatcher colour_matcher_;
};

/// The named-value columns of a CSV holding results of these metrics (csv_header): the union
/// of their value_names, in order of first appearance.
std::vector<std::string> csv_value_names(const std::vector<const MetricSpec*>& specs);

/// The most OpenMP threads a run may use: kThreadsPerCore per core the machine reports
/// (std::thread::hardware_concurrency, 1 when unknown), and never fewer than kMinThreadLimit.
/// libgomp aborts at about 33000 threads and crashes at 65536; no count near those helps.
int max_threads();
constexpr int kThreadsPerCore = 8;
constexpr int kMinThreadLimit = 64;
/// std::invalid_argument "threads: ..." unless 0 <= threads <= max_threads() (0 = all cores).
void check_thread_count(int threads);

/// Coordinates the metrics compute on safely: squared distances, and the fourth powers of
/// PCQM's quadric fit, of coordinates up to kMaxCoordinate and of boxes down to kMinBoxSide stay
/// normal doubles (1e-240 .. 1e240); beyond those they overflow or underflow and scores turn NaN.
constexpr double kMaxCoordinate = 1e60;
constexpr double kMinBoxSide = 1e-60;
/// NumericError naming `name` unless every finite coordinate is within +-kMaxCoordinate and
/// the longest side of the bounding box is 0 (left to the metric's own check) or at least
/// kMinBoxSide. Non-finite coordinates are left to the readers' and metrics' own checks.
void check_coordinate_range(const std::vector<Vec3>& positions, const std::string& name);

/// Runs a metric: checks and completes the options, reads both inputs (concurrently unless
/// run.threads == 1), computes, and fills the result's provenance (input names; seconds include
/// the reading). Errors of the computation name both inputs. A metric that reads clouds gets the
/// cloud readers' warnings before its own (mesh metrics add their readers' themselves). Checked
/// up front: the thread count (check_thread_count), the model's weights (finite), both inputs'
/// coordinates (check_coordinate_range); after: every score and pooled feature is finite
/// (NumericError naming the metric, the direction and the first non-finite value otherwise).
MetricResult run_metric(const MetricSpec& spec, const Input& reference, const Input& distorted,
                        const RunOptions& run, const OptionValues& options = {});

/// The option values of `spec` taken from a larger set (e.g. the options of every metric the
/// tool accepts): the names the metric knows, others ignored.
OptionValues options_for(const MetricSpec& spec, const OptionValues& all);

}  // namespace qm3d
