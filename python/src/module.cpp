// qm3d._qm3d: the compiled half of the Python package. It exposes the metric registry (every
// metric with its options), inputs (files recognised by content, or numpy arrays copied once),
// run() with the GIL released, and the results. The pure-Python layer (python/qm3d/__init__.py)
// turns these into qm3d.cmdm(), qm3d.pcqm(), ... with the tool's names and defaults.
#include <algorithm>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/evaluation/evaluation.h"
#include "qm3d/evaluation/evaluation_io.h"
#include "qm3d/evaluation/evaluation_protocol.h"
#include "qm3d/evaluation/orientation.h"
#include "qm3d/evaluation/pair_labels.h"
#include "qm3d/common/metric.h"
#include "qm3d/evaluation/model_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/pointcloud/metrics.h"
#include "qm3d/render/ibsm.h"
#include "qm3d/render/icid.h"
#include "qm3d/scoring/registry.h"
#include "qm3d/study/batch_row.h"
#include "interruptible_call.h"

namespace py = pybind11;

namespace qm3d::python {
namespace {
using namespace qm3d::evaluation;  // the evaluation toolkit (qm3d/evaluation/)

using scoring::default_registry;

[[noreturn]] void bad_argument(const std::string& argument, const std::string& what) {
  throw py::value_error(argument + ": " + what);
}

// An (N, 3) array of any real or integer dtype, as doubles (one copy, any strides).
template <typename Out>
std::vector<Out> rows_of_three(const py::array& a, const std::string& argument) {
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::string shape = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(a.shape(d));
    bad_argument(argument, "expected shape (N, 3), got " + shape + (a.ndim() == 1 ? ",)" : ")"));
  }
  const auto as_double = py::array_t<double, py::array::forcecast>::ensure(a);
  if (!as_double) bad_argument(argument, "expected a numeric array");
  const auto v = as_double.unchecked<2>();
  std::vector<Out> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    double* row = reinterpret_cast<double*>(&out[static_cast<std::size_t>(i)]);
    for (int k = 0; k < 3; ++k) row[k] = v(i, k);
  }
  return out;
}

std::vector<Vec3> positions_of(const py::array& a) {
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    bad_argument("positions", "expected a float array, got dtype " + std::string(py::str(a.dtype())));
  }
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  std::vector<Vec3> p = rows_of_three<Vec3>(a, "positions");
  if (p.empty()) bad_argument("positions", "no points");
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i][0]) || !std::isfinite(p[i][1]) || !std::isfinite(p[i][2])) {
      bad_argument("positions", "row " + std::to_string(i) + " is not finite (NaN or inf)");
    }
  }
  return p;
}

// uint8 colours are 0..255 (divided by 255, as the readers do); float colours are 0..1.
std::vector<Rgb> colors_of(const py::array& a, std::size_t points) {
  const char kind = a.dtype().kind();
  const bool bytes = kind == 'u' && a.itemsize() == 1;
  if (!bytes && kind != 'f') {
    bad_argument("colors", "expected uint8 (0-255) or float (0-1), got dtype " +
                               std::string(py::str(a.dtype())));
  }
  static_assert(sizeof(Rgb) == 3 * sizeof(double));
  std::vector<Rgb> c = rows_of_three<Rgb>(a, "colors");
  if (c.size() != points) {
    bad_argument("colors", std::to_string(c.size()) + " rows for " + std::to_string(points) +
                               " positions (one colour per point/vertex)");
  }
  for (std::size_t i = 0; i < c.size(); ++i) {
    for (double* v : {&c[i].r, &c[i].g, &c[i].b}) {
      if (bytes) {
        *v /= 255.0;
      } else if (!(*v >= 0.0 && *v <= 1.0)) {
        bad_argument("colors", "row " + std::to_string(i) + " has " + std::to_string(*v) +
                                   ", outside 0-1 (give uint8 for 0-255 colours)");
      }
    }
  }
  return c;
}

std::vector<Triangle> faces_of(const py::array& a, std::size_t vertices) {
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u') {
    bad_argument("faces", "expected an integer array, got dtype " + std::string(py::str(a.dtype())));
  }
  if (a.ndim() != 2 || a.shape(1) != 3) bad_argument("faces", "expected shape (F, 3)");
  const auto as_int = py::array_t<long long, py::array::forcecast>::ensure(a);
  const auto v = as_int.unchecked<2>();
  std::vector<Triangle> t(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t f = 0; f < a.shape(0); ++f) {
    for (int k = 0; k < 3; ++k) {
      const long long i = v(f, k);
      if (i < 0 || static_cast<unsigned long long>(i) >= vertices) {
        bad_argument("faces", "row " + std::to_string(f) + " refers to vertex " +
                                  std::to_string(i) + ", outside 0.." +
                                  std::to_string(vertices - 1));
      }
      t[static_cast<std::size_t>(f)][k] = static_cast<std::uint32_t>(i);
    }
  }
  return t;
}

// An input from arrays: a mesh when faces are given and `as_mesh`, else a cloud (faces ignored).
Input input_from_arrays(const py::array& positions, const py::object& colors,
                        const py::object& faces, const std::string& name, bool as_mesh) {
  std::vector<Vec3> p = positions_of(positions);
  std::vector<Rgb> c;
  if (!colors.is_none()) c = colors_of(py::array::ensure(colors), p.size());
  if (as_mesh && !faces.is_none()) {
    std::vector<Triangle> t = faces_of(py::array::ensure(faces), p.size());
    const bool has_colors = !c.empty();
    mesh::MeshFile m = mesh::mesh_from_arrays(std::move(p), std::move(c), std::move(t), name);
    return Input::from_mesh(MeshData{std::move(m.mesh), has_colors, std::move(m.warnings)}, name);
  }
  // A cloud without colours (colors None) is scored by the metrics that need none (pointssim's
  // geometry); the others refuse it naming the input.
  return Input::from_cloud(ColoredCloud{std::move(p), std::move(c)}, name);
}

py::array_t<double> as_numpy(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

template <typename Row>
py::array_t<double> rows_as_numpy(const std::vector<Row>& rows) {
  py::array_t<double> out({static_cast<py::ssize_t>(rows.size()), py::ssize_t(3)});
  if (!rows.empty()) std::memcpy(out.mutable_data(), rows.data(), rows.size() * sizeof(Row));
  return out;
}

py::array_t<std::uint32_t> faces_as_numpy(const std::vector<Triangle>& t) {
  py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(t.size()), py::ssize_t(3)});
  if (!t.empty()) std::memcpy(out.mutable_data(), t.data(), t.size() * sizeof(Triangle));
  return out;
}

py::dict spec_dict(const MetricSpec& s) {
  py::dict d;
  d["name"] = s.name;
  d["title"] = s.title;
  d["summary"] = s.summary;
  d["applies_to"] = s.applies_to == AppliesTo::kMeshes   ? "meshes"
                    : s.applies_to == AppliesTo::kClouds ? "clouds"
                                                         : "both";
  d["reads"] = s.reads == Input::Kind::kMesh ? "mesh" : "cloud";
  d["reads_two_meshes_as_meshes"] = s.reads_two_meshes_as_meshes;
  d["reads_each_as_is"] = s.reads_each_as_is;
  d["default_direction"] = direction_name(s.default_direction);
  d["direction_help"] = s.direction_help;
  d["takes_model"] = s.takes_model;
  d["model_metric"] = s.model_name();
  d["value_names"] = s.value_names;
  d["higher_is_better"] = s.higher_is_better;
  d["reproduces"] = s.reproduces;
  d["quality_value_names"] = s.quality_value_names;
  py::list options;
  for (const OptionSpec& o : s.options) {
    py::dict od;
    od["name"] = o.name;
    od["help"] = o.help;
    od["default"] = o.default_value.dump();  // JSON text; the Python layer decodes it
    od["choices"] = o.choices;
    od["min"] = o.min;
    od["max"] = o.max;
    od["min_exclusive"] = o.min_exclusive;
    options.append(od);
  }
  d["options"] = options;
  return d;
}

struct RunArguments {
  std::string options_json;
  std::optional<std::string> direction;
  int threads = 0;
  bool per_element = false;
  std::string data_dir;
  std::optional<std::vector<double>> weights;
  std::optional<std::string> model_path;
  py::object progress;
  /// The caller is done with both inputs: what was read from their files is freed as soon as the
  /// metric holds its own copies.
  bool release_inputs = false;
};

MetricResult run(const std::string& metric, const Input& reference, const Input& distorted,
                 const RunArguments& a) {
  const MetricSpec& spec = default_registry().get(metric);
  RunOptions run;
  if (a.direction) run.direction = parse_direction(*a.direction);
  if (a.threads < 0) throw py::value_error("threads: must be 0 (all cores) or more");
  run.threads = a.threads;
  run.per_element = a.per_element;
  run.data_dir = a.data_dir;
  if (a.weights && a.model_path) throw py::value_error("give weights or model, not both");
  if (a.weights) {
    if (a.weights->size() != kNumFeatures) throw py::value_error("weights: expected 8 numbers");
    LinearModel m;
    m.metric = spec.model_name();
    std::copy(a.weights->begin(), a.weights->end(), m.weights.begin());
    m.provenance = "weights=";
    run.model = m;
  } else if (a.model_path) {
    run.model = read_model_for(*a.model_path, spec.model_name());
  }
  // The user's callback, released with the GIL held wherever its last holder ends (a worker
  // whose caller was interrupted may outlive the call).
  std::shared_ptr<py::object> callback;
  if (!a.progress.is_none()) {
    callback.reset(new py::object(a.progress), [](py::object* o) {
      py::gil_scoped_acquire gil;
      delete o;
    });
  }
  const nlohmann::json options = nlohmann::json::parse(a.options_json);
  // Copies of the handles: the worker keeps the inputs alive even if Python drops them.
  const Input ref = reference, dist = distorted;
  const bool release_inputs = a.release_inputs;
  return call_interruptibly<MetricResult>(
      [&spec, run, options, callback, ref, dist, release_inputs](
          const std::atomic<bool>& cancelled) mutable {
        // Every stage boundary checks for Ctrl-C; the user's callback (if any) is called with
        // the GIL, from the worker thread.
        run.progress = [&cancelled, callback](const std::string& stage, double fraction) {
          if (cancelled) throw CallCancelled();
          if (!callback) return;
          py::gil_scoped_acquire gil;
          if (cancelled) throw CallCancelled();
          (*callback)(stage, fraction);
        };
        if (release_inputs) {
          run.inputs_done = [ref, dist] {
            ref.release();
            dist.release();
          };
        }
        return run_metric(spec, ref, dist, run, options);
      });
}

/// An H x W x 3 or x 4 uint8 array (C order; the package checks it) as an RGB image, alpha
/// dropped.
render::RgbImage rgb_image_of(const py::array_t<std::uint8_t, py::array::c_style>& a,
                              const std::string& argument) {
  if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4) || a.shape(0) < 1 || a.shape(1) < 1) {
    throw std::invalid_argument(argument + ": expected an (H, W, 3) or (H, W, 4) uint8 array");
  }
  render::RgbImage out{static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), {}};
  const std::size_t pixels = static_cast<std::size_t>(out.width) * out.height;
  const std::size_t channels = static_cast<std::size_t>(a.shape(2));
  out.rgb.resize(pixels * 3);
  const std::uint8_t* p = a.data();
  for (std::size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) out.rgb[i * 3 + c] = p[i * channels + c];
  }
  return out;
}

}  // namespace

// The typed errors and the registry's metrics.
void bind_errors_and_metrics(py::module_& m) {
  // Typed errors: a file that cannot be read is an OSError, bad content a ValueError.
  py::register_exception<InputError>(m, "InputError", PyExc_OSError);
  py::register_exception<FormatError>(m, "FormatError", PyExc_ValueError);
  py::register_exception<NumericError>(m, "NumericError", PyExc_ValueError);

  m.def("metrics", [] {
    py::list out;
    for (const MetricSpec& s : default_registry().metrics()) out.append(spec_dict(s));
    return out;
  });
}

// Inputs: read by content or built from arrays, and the metrics that apply.
void bind_inputs(py::module_& m) {
  py::class_<Input>(m, "Input")
      .def_static(
          "from_file",
          [](const std::string& path, const std::string& colour_scale, const std::string& texture,
             const std::string& texture_option) {
            ReadOptions o;
            o.colour_scale = parse_colour_scale(colour_scale);  // ValueError otherwise
            o.texture = texture;
            o.texture_option = texture_option;
            return default_registry().read(path, o);
          },
          py::arg("path"), py::arg("colour_scale") = "auto", py::arg("texture") = "",
          py::arg("texture_option") = "ref_texture= / dist_texture=")
      .def_static("from_arrays", &input_from_arrays, py::arg("positions"), py::arg("colors"),
                  py::arg("faces"), py::arg("name"), py::arg("as_mesh"))
      .def_property_readonly("name", &Input::name)
      .def_property_readonly("kind",
                             [](const Input& in) { return in.is_mesh() ? "mesh" : "cloud"; })
      .def("mesh_arrays",
           [](const Input& in) {
             const MeshData& m = [&]() -> const MeshData& {
               py::gil_scoped_release release;
               return in.mesh();
             }();
             return py::make_tuple(rows_as_numpy(m.mesh.positions),
                                   m.has_colors ? py::object(rows_as_numpy(m.mesh.colors))
                                                : py::object(py::none()),
                                   faces_as_numpy(m.mesh.triangles), m.warnings);
           })
      .def("cloud_arrays", [](const Input& in) {
        const ColoredCloud& c = [&]() -> const ColoredCloud& {
          py::gil_scoped_release release;
          return in.cloud();
        }();
        return py::make_tuple(rows_as_numpy(c.positions), rows_as_numpy(c.colors),
                              in.cloud_warnings());
      });

  m.def("applicable", [](const Input& ref, const Input& dist) {
    std::vector<std::string> names;
    for (const MetricSpec* s : default_registry().applicable(ref, dist)) names.push_back(s->name);
    return names;
  });
}

// Results and the rows of `qm3d batch`.
void bind_results(py::module_& m) {
  py::class_<DirectionResult>(m, "DirectionResult")
      .def_readonly("score", &DirectionResult::score)
      .def_readonly("box_size", &DirectionResult::box_size)
      .def_property_readonly("feature_values",
                             [](const DirectionResult& d) {
                               return std::vector<double>(d.features.begin(), d.features.end());
                             })
      .def_property_readonly("per_element", [](const DirectionResult& d) -> py::object {
        if (d.per_element.empty()) return py::none();
        return as_numpy(d.per_element);
      })
      .def_readonly("values", &DirectionResult::values)
      .def_property_readonly("per_element_values", [](const DirectionResult& d) {
        py::dict out;
        for (const auto& [name, v] : d.per_element_values) out[py::str(name)] = as_numpy(v);
        return out;
      })
      .def_property_readonly("element_positions", [](const DirectionResult& d) -> py::object {
        if (d.element_positions.empty()) return py::none();
        return rows_as_numpy(d.element_positions);
      });

  py::class_<MetricResult>(m, "MetricResult")
      .def_readonly("metric", &MetricResult::metric)
      .def_readonly("score", &MetricResult::score)
      .def_readonly("dist_to_ref", &MetricResult::dist_to_ref)
      .def_readonly("ref_to_dist", &MetricResult::ref_to_dist)
      .def_readonly("feature_names", &MetricResult::feature_names)
      .def_readonly("warnings", &MetricResult::warnings)
      .def_property_readonly("seconds",
                             [](const MetricResult& r) { return r.provenance.seconds; })
      .def_readonly("values", &MetricResult::values)
      .def_property_readonly("details_json", [](const MetricResult& r) { return r.details.dump(); })
      .def("to_json", [](const MetricResult& r) { return to_json(r).dump(); })
      .def(
          "csv_row",
          [](const MetricResult& r, const std::vector<std::string>& value_names) {
            return study::csv_row(r, {}, value_names);
          },
          py::arg("value_names") = std::vector<std::string>{});

  m.def("csv_header", &study::csv_header, py::arg("value_names") = std::vector<std::string>{});
  // The error row of `qm3d batch` (result_io.h): qm3d.dask makes its rows only through these.
  m.def("csv_error_row", &study::csv_error_row, py::arg("reference"), py::arg("distorted"),
        py::arg("metric"), py::arg("error"),
        py::arg("value_names") = std::vector<std::string>{});
  m.def("csv_value_names", [] {
    std::vector<const MetricSpec*> all;
    for (const MetricSpec& s : default_registry().metrics()) all.push_back(&s);
    return csv_value_names(all);
  });
}

// Running a metric, and the calls Ctrl-C left running.
void bind_scoring(py::module_& m) {
  m.def(
      "run",
      [](const std::string& metric, const Input& reference, const Input& distorted,
         const std::string& options_json, std::optional<std::string> direction, int threads,
         bool per_element, const std::string& data_dir, std::optional<std::vector<double>> weights,
         std::optional<std::string> model_path, py::object progress, bool release_inputs) {
        return run(metric, reference, distorted,
                   RunArguments{options_json, std::move(direction), threads, per_element,
                                data_dir, std::move(weights), std::move(model_path),
                                std::move(progress), release_inputs});
      },
      py::arg("metric"), py::arg("reference"), py::arg("distorted"), py::arg("options_json"),
      py::arg("direction"), py::arg("threads"), py::arg("per_element"), py::arg("data_dir"),
      py::arg("weights"), py::arg("model_path"), py::arg("progress"),
      py::arg("release_inputs") = false);


  // Called at interpreter exit (python/qm3d/__init__.py): metric calls interrupted by Ctrl-C
  // finish their current stage on their own threads; they must be gone before Python is.
  m.def("wait_for_interrupted_calls", [] {
    py::gil_scoped_release release;
    AbandonedWorkers::instance().wait_all();
  });
}

// Surface and grid sampling.
void bind_sampling(py::module_& m) {
  m.def(
      "sample",
      [](const Input& mesh, std::size_t points, double density, std::uint64_t seed) {
        ColoredCloud c;
        {
          py::gil_scoped_release release;
          c = default_registry().sampler()(mesh, SurfaceSampling{points, density, seed});
        }
        return py::make_tuple(rows_as_numpy(c.positions), rows_as_numpy(c.colors));
      },
      py::arg("mesh"), py::arg("points"), py::arg("density"), py::arg("seed"));

  m.def(
      "sample_grid",
      [](const Input& mesh, int grid_size, std::optional<std::vector<double>> box, bool all_axes,
         bool bilinear) {
        GridSamplingOptions o;
        o.grid_size = grid_size;
        o.all_axes = all_axes;
        o.bilinear = bilinear;
        if (box) {
          if (box->size() != 6) throw std::invalid_argument("box: 6 numbers (min x y z, max x y z)");
          FloatBox b;
          for (int k = 0; k < 3; ++k) {
            b.min[k] = static_cast<float>((*box)[k]);
            b.max[k] = static_cast<float>((*box)[3 + k]);
          }
          o.box = b;
        }
        GridSamples g;
        {
          py::gil_scoped_release release;
          g = default_registry().grid_sampler()(mesh, o);
        }
        std::vector<Vec3> p(g.positions.size()), n(g.normals.size());
        for (std::size_t i = 0; i < p.size(); ++i) {
          for (int k = 0; k < 3; ++k) {
            p[i][k] = g.positions[i][k];
            n[i][k] = g.normals[i][k];
          }
        }
        std::vector<Rgb> c(g.colours.size());
        for (std::size_t i = 0; i < c.size(); ++i) {
          c[i] = {g.colours[i][0] / 255.0, g.colours[i][1] / 255.0, g.colours[i][2] / 255.0};
        }
        py::list warnings;
        for (const std::string& w : g.warnings) warnings.append(w);
        return py::make_tuple(rows_as_numpy(p), rows_as_numpy(n), rows_as_numpy(c), warnings,
                              g.degenerate_faces, g.step);
      },
      py::arg("mesh"), py::arg("grid_size"), py::arg("box"), py::arg("all_axes"),
      py::arg("bilinear"));
}

// The rendered views of IBSM.
void bind_render_views(py::module_& m) {
  m.def(
      "render_views",
      [](const Input& input, const std::string& options_json, std::optional<std::vector<double>> frame,
         int threads) {
        const MetricSpec& spec = default_registry().get("ibsm");
        const render::IbsmOptions o =
            render::ibsm_options(spec.complete(nlohmann::json::parse(options_json)));
        std::vector<render::View> views;
        render::Frame f;
        std::vector<render::Float3> dirs;
        {
          py::gil_scoped_release release;
          const render::RenderModel model = render::model_of(input, o.splats);
          if (frame) {
            if (frame->size() != 4 || !(std::isfinite((*frame)[3]) && (*frame)[3] > 0)) {
              throw std::invalid_argument("frame: (centre x, y, z, radius > 0)");
            }
            for (int k = 0; k < 3; ++k) f.center[k] = static_cast<float>((*frame)[k]);
            f.radius = static_cast<float>((*frame)[3]);
          } else {
            f = render::frame_of(model, model);
          }
          dirs = render::view_directions(o);
          views = render::render_views(model, f, dirs, {o.resolution, o.culling, o.lighting},
                                       threads);
        }
        py::list out;
        for (std::size_t i = 0; i < views.size(); ++i) {
          const render::View& v = views[i];
          const py::ssize_t h = v.height, w = v.width;
          py::array_t<std::uint8_t> rgba({h, w, py::ssize_t{4}});
          py::array_t<float> depth({h, w});
          auto px = rgba.mutable_unchecked<3>();
          auto dz = depth.mutable_unchecked<2>();
          for (py::ssize_t y = 0; y < h; ++y) {
            const std::size_t row = static_cast<std::size_t>(h - 1 - y) * v.width;  // top first
            for (py::ssize_t x = 0; x < w; ++x) {
              const std::size_t k = row + static_cast<std::size_t>(x);
              for (int c = 0; c < 4; ++c) px(y, x, c) = v.rgba[k * 4 + c];
              dz(y, x) = v.rgba[k * 4 + 3] ? v.depth[k] : std::numeric_limits<float>::quiet_NaN();
            }
          }
          out.append(py::make_tuple(std::vector<float>(dirs[i].begin(), dirs[i].end()), rgba,
                                    depth, v.depth_range));
        }
        return py::make_tuple(out, std::vector<float>(f.center.begin(), f.center.end()), f.radius);
      },
      py::arg("input"), py::arg("options_json"), py::arg("frame"), py::arg("threads"));
}

// Image quality of two images (iCID, SSIM).
void bind_image_quality(py::module_& m) {
  m.def(
      "image_quality",
      [](const py::array_t<std::uint8_t, py::array::c_style>& a,
         const py::array_t<std::uint8_t, py::array::c_style>& b, const std::string& intent,
         bool iam, bool omit_maps67, bool downsampling, bool keep_map, int threads,
         const std::string& data_dir) {
        const render::RgbImage ia = rgb_image_of(a, "a"), ib = rgb_image_of(b, "b");
        if (ia.width != ib.width || ia.height != ib.height) {
          throw std::invalid_argument("b: " + std::to_string(ib.height) + " x " +
                                      std::to_string(ib.width) + " pixels, a has " +
                                      std::to_string(ia.height) + " x " + std::to_string(ia.width) +
                                      " (the same size needed)");
        }
        render::IcidOptions o;
        o.intent = render::icid_intent(intent);
        o.iam = iam;
        o.omit_maps67 = omit_maps67;
        o.downsampling = downsampling;
        o.keep_map = keep_map;
        o.threads = threads;
        render::ImageScores s;
        {
          py::gil_scoped_release release;
          const auto table = Lab2000hlTable::shared(render::icid_table_dir(data_dir));
          s = render::image_scores(ia, ib, *table, o);
        }
        py::dict values;
        values["icid"] = s.icid.icid;
        for (int k = 0; k < 7; ++k) values[py::str(render::icid_map_names()[k])] = s.icid.maps[k];
        values["ssim"] = s.ssim;
        values["ms_ssim"] = s.ms_ssim;
        values["psnr"] = s.psnr;
        py::object map = py::none();
        if (keep_map) {
          py::array_t<double> m({static_cast<py::ssize_t>(s.icid.map_height),
                                 static_cast<py::ssize_t>(s.icid.map_width)});
          std::memcpy(m.mutable_data(), s.icid.map.data(), s.icid.map.size() * sizeof(double));
          map = m;
        }
        return py::make_tuple(values, map);
      },
      py::arg("a"), py::arg("b"), py::arg("intent"), py::arg("iam"), py::arg("omit_maps67"),
      py::arg("downsampling"), py::arg("keep_map"), py::arg("threads"), py::arg("data_dir"));
}

// Agreement of one metric's scores with subjective scores.
void bind_evaluation(py::module_& m) {
  m.def(
      "evaluate",
      [](const std::vector<double>& scores, const std::vector<double>& mos,
         const std::vector<double>& ci95, std::size_t bootstrap, std::uint64_t seed) {
        EvaluationOptions o;
        o.bootstrap = bootstrap;
        o.seed = seed;
        EvaluationResult r;
        {
          py::gil_scoped_release release;
          r = evaluate_scores(scores, mos, ci95, o);
        }
        nlohmann::ordered_json j;
        j["stimuli"] = r.count;
        for (const auto& [name, s] : named_statistics(r)) j["statistics"][name] = statistic_json(s);
        j["logistic"] = logistic_json(r.fit);
        j["bootstrap"] = {{"replicates", r.bootstrap_replicates},
                          {"used", r.bootstrap_used},
                          {"seed", seed},
                          {"confidence", o.confidence}};
        return j.dump();
      },
      py::arg("scores"), py::arg("mos"), py::arg("ci95"), py::arg("bootstrap"), py::arg("seed"));
}

// Several metrics on one set of stimuli (the protocol, Krasula's pairs), and model files.
void bind_evaluate_metrics(py::module_& m) {
  m.def(
      "evaluate_metrics",
      [](const std::vector<std::string>& names, const std::vector<std::vector<double>>& scores,
         const std::vector<std::string>& lower_is_better, const std::string& orientation,
         const std::vector<double>& mos, const std::vector<double>& ci95, const std::string& labels,
         const std::vector<double>& sd, const std::vector<double>& n,
         const std::vector<std::vector<double>>& raw, const std::vector<std::size_t>& first,
         const std::vector<std::size_t>& second, const std::vector<int>& label,
         const std::vector<std::string>& groups, std::size_t bootstrap, std::uint64_t seed,
         const std::string& mapping) {
        const OrientationRequest request{lower_is_better, orientation, "lower_is_better",
                                         "orientation"};
        std::vector<MetricScores> metrics;
        for (std::size_t i = 0; i < names.size(); ++i) {
          const Orientation r = orient(default_registry(), request, {names[i], "", names[i]},
                                       Fallback::column_name_then_quality);
          metrics.push_back({names[i], scores.at(i), *r.higher_is_better, r.source});
        }
        PairLabelSource source;
        if (labels == "sd") source = {PairLabelSource::Kind::sd, sd, n, {}, {}};
        if (labels == "raw") source = {PairLabelSource::Kind::raw, {}, {}, raw, {}};
        if (labels == "pairs") {
          source.kind = PairLabelSource::Kind::given;
          source.given.rule = "given";
          for (std::size_t k = 0; k < label.size(); ++k) {
            source.given.add(first.at(k), second.at(k), label[k]);
          }
        }
        const SubjectiveData subjective{mos, ci95, label_pairs(mos, source, groups)};
        ProtocolOptions o;
        o.evaluation.bootstrap = bootstrap;
        o.evaluation.seed = seed;
        o.mapping = parse_mapping(mapping);
        nlohmann::ordered_json j;
        {
          py::gil_scoped_release release;
          j = evaluate_metrics(metrics, subjective, o);
        }
        return j.dump();
      },
      py::arg("names"), py::arg("scores"), py::arg("lower_is_better"), py::arg("orientation"),
      py::arg("mos"), py::arg("ci95"), py::arg("labels"), py::arg("sd"), py::arg("n"),
      py::arg("raw"), py::arg("first"), py::arg("second"), py::arg("label"), py::arg("groups"),
      py::arg("bootstrap"), py::arg("seed"), py::arg("mapping") = "logistic4");

  m.def("load_model", [](const std::string& path) { return model_to_json(read_model(path)); },
        py::arg("path"));
}

}  // namespace qm3d::python

PYBIND11_MODULE(_qm3d, m) {
  using namespace qm3d;
  using namespace qm3d::python;
  m.doc() = "qm3d's compiled core; use the qm3d package, not this module.";
  m.attr("__version__") = kVersion;
  m.attr("__commit__") = git_commit();
  bind_errors_and_metrics(m);
  bind_inputs(m);
  bind_results(m);
  bind_scoring(m);
  bind_sampling(m);
  bind_render_views(m);
  bind_image_quality(m);
  bind_evaluation(m);
  bind_evaluate_metrics(m);
}
