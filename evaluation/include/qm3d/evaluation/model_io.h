// Model files: the feature weights of a metric as JSON, so that weights trained with
// `qm3d train` replace the built-in ones (`qm3d cmdm --model FILE`, `qm3d pcqm --model FILE`).
// The built-in models are such files too: data/models/cmdm.json and data/models/pcqm.json hold
// exactly cmdm_model() and pcqm_model() (a test checks it).
//
// Format (keys other than these are an error, so a misspelt key never goes unnoticed):
//   {
//     "format": "qm3d-model/1",            optional; when present it must be this
//     "metric": "pcqm",                    which metric's features the weights apply to
//     "features": ["f3", "f4", "f6"],      f1..f8 (F1..F8 accepted), each at most once
//     "weights": [0.0057, 0.9771, 0.0172], one per feature; unlisted features weigh 0
//     "provenance": "...",                 where the weights come from
//     "logistic": {"beta1": .., "beta2": .., "beta3": .., "beta4": ..}
//                                          optional: score -> MOS mapping found in training
//   }
//
// Example:
//   const qm3d::LinearModel m = qm3d::read_model_for("trained.json", "pcqm");
//   double score = m.apply(features);
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/common/pooling.h"

namespace qm3d::evaluation {

/// The "format" value written by write_model.
inline constexpr const char* kModelFormat = "qm3d-model/1";

struct ModelFile {
  LinearModel model;
  /// The logistic mapping score -> MOS fitted with the weights (informative; not used to score).
  std::optional<LogisticFunction> mos_mapping;
};

/// Parses the JSON text of a model file. `source` (a path) prefixes every error message.
/// @throws FormatError  not JSON, a missing or unknown key, a wrong type, an unknown or repeated
///                      feature name, features and weights of different lengths, a non-finite
///                      weight, or no weight at all
ModelFile parse_model(const std::string& json_text, const std::string& source);

/// Reads and parses a model file. @throws InputError (unreadable) or FormatError (as above).
ModelFile read_model(const std::filesystem::path& path);

/// Reads a model file and checks that it is for `metric` ("cmdm", "pcqm"); the provenance
/// returned is the file's, followed by "(model file PATH)".
/// @throws FormatError  as read_model, or the file is for another metric
LinearModel read_model_for(const std::filesystem::path& path, const std::string& metric);

/// The JSON text of a model (2-space indented, newline-terminated); only the features with a
/// non-zero weight are listed, in f1..f8 order. Weights are written in shortest round-trip form.
std::string model_to_json(const ModelFile& model);

/// Writes model_to_json(model) atomically. @throws InputError when the file cannot be written.
void write_model(const std::filesystem::path& path, const ModelFile& model);

/// "f1".."f8" (or "F1".."F8") -> 0..7. @throws FormatError naming `name` otherwise.
std::size_t feature_index(const std::string& name);

/// 0..7 -> "f1".."f8".
std::string feature_name(std::size_t index);

}  // namespace qm3d::evaluation
