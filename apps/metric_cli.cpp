#include "metric_cli.h"

#include <algorithm>
#include <set>
#include <sstream>

#include "qm3d/evaluation/model_io.h"

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
using namespace qm3d::evaluation;  // NOLINT: the library this command prints
namespace {

constexpr const char* kModelHelp =
    "Model file (JSON: metric, features, weights; e.g. written by qm3d train) used instead of the "
    "built-in weights";

// Adds --NAME for each option of `specs`, once per name (compare/batch take the options of every
// metric; a value given applies to each metric that has an option of that name).
// CLI11's check of a number option: its range, or its sign when the range is open-ended.
CLI::Validator range_check(const OptionSpec& o) {
  constexpr double kOpenEnded = 1e12;
  if (o.max >= kOpenEnded && o.min == 0) {
    return o.min_exclusive ? CLI::Validator(CLI::PositiveNumber)
                           : CLI::Validator(CLI::NonNegativeNumber);
  }
  if (o.max >= kOpenEnded && o.min == 1 && o.default_value.is_number_integer()) {
    return CLI::PositiveNumber;
  }
  if (o.default_value.is_number_integer()) {
    return CLI::Range(static_cast<long long>(o.min), static_cast<long long>(o.max));
  }
  return CLI::Range(o.min, o.max);
}

// The help of an option: its metric's, or each metric's when several have an option of that
// name with different help ("cmdm: ...; msdm2: ...").
std::string option_help(const std::vector<const MetricSpec*>& specs, const std::string& name) {
  std::vector<std::pair<std::string, std::string>> helps;
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      if (o.name != name) continue;
      const bool seen = std::any_of(helps.begin(), helps.end(),
                                    [&](const auto& h) { return h.second == o.help; });
      if (!seen) helps.emplace_back(spec->name, o.help);
    }
  }
  if (helps.size() == 1) return helps.front().second;
  std::string text;
  for (const auto& [metric, help] : helps) text += (text.empty() ? "" : "; ") + metric + ": " + help;
  return text;
}

// The option with the widest range among the metrics that have one of its name (psnr's
// neighbours 1..2, pointssim's 3..): the tool takes a value any of them accepts, and each
// metric checks its own range when it runs (MetricSpec::complete).
OptionSpec widest_range(const std::vector<const MetricSpec*>& specs, OptionSpec o) {
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& other : spec->options) {
      if (other.name != o.name || !other.default_value.is_number()) continue;
      if (other.min < o.min) {
        o.min = other.min;
        o.min_exclusive = other.min_exclusive;
      } else if (other.min == o.min) {
        o.min_exclusive = o.min_exclusive && other.min_exclusive;
      }
      o.max = std::max(o.max, other.max);
    }
  }
  return o;
}

}  // namespace

std::string cli_flag(const std::string& option) {
  std::string flag = "--" + option;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

std::vector<const MetricSpec*> all_metrics() {
  std::vector<const MetricSpec*> all;
  for (const auto& m : default_registry().metrics()) all.push_back(&m);
  return all;
}

std::vector<const MetricSpec*> compare_metrics() {
  std::vector<const MetricSpec*> out;
  for (const auto& m : default_registry().metrics()) {
    if (m.in_compare) out.push_back(&m);
  }
  return out;
}

namespace {

// The help heading of the options a metric brings to a command of several metrics ("Options
// of PCQM (pcqm)"; an option several metrics take is under the first); one metric's command
// keeps CLI11's single heading.
std::string option_group(const std::vector<const MetricSpec*>& specs, const MetricSpec& spec) {
  if (specs.size() < 2) return "Options";
  return "Options of " + spec.title + " (" + spec.name + ")";
}

}  // namespace

void add_metric_options(CLI::App* cmd, const std::vector<const MetricSpec*>& specs,
                        MetricOptionsCli& cli) {
  std::set<std::string> added;
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      if (!added.insert(o.name).second) continue;
      cmd->option_defaults()->group(option_group(specs, *spec));
      const std::string flag = cli_flag(o.name);
      const std::string help = option_help(specs, o.name);
      const nlohmann::json& d = o.default_value;
      if (d.is_boolean()) {
        cli.given[o.name] = cmd->add_flag(flag, cli.flags[o.name], help);
        continue;
      }
      if (d.is_array()) {
        // A fixed-length list: `--rotation 30 60 45` or `--rotation 30,60,45`.
        const int n = static_cast<int>(d.size());
        CLI::Option* opt = cmd->add_option(flag, cli.lists[o.name], help)
                               ->expected(1, n)
                               ->delimiter(',')
                               ->type_name("NUM x" + std::to_string(n))
                               ->default_str(d.dump());
        cli.given[o.name] = opt;
        continue;
      }
      CLI::Option* opt = cmd->add_option(flag, cli.text[o.name], help);
      {
        opt->default_str(d.is_string() ? d.get<std::string>() : d.dump());
      }
      if (!o.choices.empty()) opt->check(CLI::IsMember(o.choices));
      if (d.is_number()) {
        opt->type_name(d.is_number_integer() ? "INT" : "FLOAT");
        opt->check(range_check(widest_range(specs, o)));
      }
      cli.given[o.name] = opt;
    }
  }
  cmd->option_defaults()->group("Options");
}

// The options given, converted to their types (checked later against each metric's spec).
OptionValues metric_option_values(const std::vector<const MetricSpec*>& specs,
                                  const MetricOptionsCli& cli) {
  OptionValues values = OptionValues::object();
  for (const MetricSpec* spec : specs) {
    for (const OptionSpec& o : spec->options) {
      const auto it = cli.given.find(o.name);
      if (it == cli.given.end() || it->second->count() == 0 || values.contains(o.name)) continue;
      const nlohmann::json& d = o.default_value;
      if (d.is_boolean()) {
        values[o.name] = cli.flags.at(o.name);
        continue;
      }
      std::string text;
      if (d.is_array()) {
        for (const std::string& item : cli.lists.at(o.name)) text += (text.empty() ? "" : ",") + item;
      } else {
        text = cli.text.at(o.name);
      }
      const auto bad = [&] {
        return std::invalid_argument(cli_flag(o.name) + ": '" + text + "' is not " +
                                     (d.is_number_integer() ? "an integer"
                                      : d.is_number()       ? "a number"
                                                            : "a list of numbers"));
      };
      try {
        std::size_t used = 0;
        if (d.is_number_integer()) {
          const long long v = std::stoll(text, &used);
          if (used != text.size()) throw bad();
          values[o.name] = v;
        } else if (d.is_number()) {
          const double v = std::stod(text, &used);
          if (used != text.size()) throw bad();
          values[o.name] = v;
        } else if (d.is_array()) {
          nlohmann::json list = nlohmann::json::array();
          std::stringstream in(text);
          std::string item;
          while (std::getline(in, item, ',')) {
            list.push_back(std::stod(item, &used));
            if (used != item.size()) throw bad();
          }
          values[o.name] = list;
        } else {
          values[o.name] = text;
        }
      } catch (const std::logic_error&) {  // std::stod's invalid_argument / out_of_range
        throw bad();
      }
    }
  }
  return values;
}

void add_run_options(CLI::App* cmd, RunCli& r, const MetricSpec* spec) {
  const std::string help =
      spec ? spec->direction_help + " (default " + direction_name(spec->default_direction) + ")"
           : "symmetric, dist-to-ref or ref-to-dist, for every metric (default: each metric's "
             "own: CMDM symmetric, MSDM2 dist-to-ref, PCQM ref-to-dist)";
  auto* direction = cmd->add_option("--direction", r.direction, help)
                        ->check(CLI::IsMember({"symmetric", "dist-to-ref", "ref-to-dist"}));
  cmd->add_flag("--symmetric", r.symmetric, "Same as --direction symmetric")->excludes(direction);
  if (spec && !spec->takes_model) return;
  CLI::Option* weights = nullptr;
  if (spec) {
    weights = cmd->add_option("--weights", r.weights,
                                       "Weights of the 8 features replacing the published model")
                           ->expected(8)
                           ->delimiter(',');
  }
  auto* model = cmd->add_option("--model", r.model_file,
                                spec ? std::string(kModelHelp)
                                     : std::string(kModelHelp) +
                                           "; applies to the metric the file names")
                    ->type_name("MODEL.json");
  if (weights) model->excludes(weights);
}

void add_read_options(CLI::App* cmd, std::string& colour_scale) {
  cmd->add_option("--colour-scale", colour_scale,
                  "Scale of colours stored as numbers (OBJ, OFF, PLY float): auto = the "
                  "reference's rule (0..255 when any value is above 1, else 0..1; warns when few "
                  "values decide), unit = 0..1 (values above 1 clamped), byte = 0..255")
      ->check(CLI::IsMember({"auto", "unit", "byte"}))
      ->capture_default_str();
}

void add_texture_options(CLI::App* cmd, std::string& ref_texture, std::string& dist_texture) {
  const std::string what =
      " texture map (PNG, JPEG, BMP, TGA): replaces the map of every material of that mesh, "
      "every face with texture coordinates takes its colour from it (mmetric's --inputMap";
  cmd->add_option("--ref-texture", ref_texture, "The reference's" + what + "A)")
      ->type_name("FILE");
  cmd->add_option("--dist-texture", dist_texture, "The distorted's" + what + "B)")
      ->type_name("FILE");
}

ReadOptions read_options(const std::string& colour_scale, const std::string& texture,
                         const std::string& texture_option) {
  ReadOptions o = read_options(colour_scale);
  o.texture = texture;
  o.texture_option = texture_option;
  return o;
}

ReadOptions read_options(const std::string& colour_scale) {
  ReadOptions o;
  o.colour_scale = parse_colour_scale(colour_scale);
  return o;
}

ScoreRequest score_request(const RunCli& r, const MetricSpec* spec, int threads,
                           const std::string& data_dir) {
  ScoreRequest req;
  req.run.threads = threads;
  req.run.data_dir = data_dir;
  if (r.symmetric) req.run.direction = Direction::kSymmetric;
  if (!r.direction.empty()) req.run.direction = parse_direction(r.direction);
  if (!r.weights.empty()) {
    LinearModel m;
    m.metric = spec->model_name();
    std::copy(r.weights.begin(), r.weights.end(), m.weights.begin());
    m.provenance = "--weights";
    req.model = m;
    req.model_any_metric = true;
  } else if (!r.model_file.empty()) {
    const std::string metric = spec ? spec->model_name() : read_model(r.model_file).model.metric;
    req.model = read_model_for(r.model_file, metric);
    req.model_any_metric = spec != nullptr;
  }
  return req;
}

}  // namespace qm3d::app
