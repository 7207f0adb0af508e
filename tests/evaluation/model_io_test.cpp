#include "qm3d/evaluation/model_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "qm3d/common/error.h"
#include "test_paths.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

namespace fs = std::filesystem;

// The message of the FormatError that parsing `text` throws ("" when it does not throw).
std::string parse_error(const std::string& text) {
  try {
    parse_model(text, "m.json");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelIo, BuiltInModelFilesHoldTheBuiltInWeights) {
  for (const LinearModel* builtin : {&cmdm_model(), &pcqm_model()}) {
    const fs::path file = test::source_dir() / "data" / "models" / (builtin->metric + ".json");
    const ModelFile m = read_model(file);
    EXPECT_EQ(m.model.metric, builtin->metric);
    EXPECT_EQ(m.model.weights, builtin->weights) << file;  // bit-identical
    EXPECT_EQ(m.model.provenance, builtin->provenance);
    EXPECT_FALSE(m.mos_mapping.has_value());
  }
}

TEST(ModelIo, RoundTripIsExact) {
  ModelFile m;
  m.model = {"pcqm", {0, 0.1 / 3, 0, 1e-300, 0, -2.5, 0, 0.7}, "test \"quoted\""};
  m.mos_mapping = LogisticFunction{1.25, 4.5, 0.0123456789, 0.00321};
  const fs::path file = fs::temp_directory_path() /
                        ("qm3d_model_io_round_trip_" + std::to_string(::getpid()) + ".json");
  write_model(file, m);
  const ModelFile back = read_model(file);
  fs::remove(file);
  EXPECT_EQ(back.model.metric, "pcqm");
  EXPECT_EQ(back.model.weights, m.model.weights);
  EXPECT_EQ(back.model.provenance, m.model.provenance);
  ASSERT_TRUE(back.mos_mapping.has_value());
  EXPECT_EQ(back.mos_mapping->beta3, 0.0123456789);
  EXPECT_EQ(back.mos_mapping->beta4, 0.00321);
}

TEST(ModelIo, WritesOnlyTheUsedFeatures) {
  const std::string text = model_to_json({pcqm_model(), std::nullopt});
  EXPECT_NE(text.find("\"features\": [\n    \"f3\",\n    \"f4\",\n    \"f6\"\n  ]"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\"format\": \"qm3d-model/1\""), std::string::npos);
}

TEST(ModelIo, ReadModelForChecksTheMetric) {
  const fs::path file = test::source_dir() / "data" / "models" / "pcqm.json";
  const LinearModel m = read_model_for(file, "pcqm");
  EXPECT_EQ(m.weights, pcqm_model().weights);
  EXPECT_NE(m.provenance.find(file.string()), std::string::npos);
  try {
    read_model_for(file, "cmdm");
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("pcqm.json: model file: it is a \"pcqm\" model"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(read_model("/nonexistent/model.json"), InputError);
}

TEST(ModelIo, ErrorsNameTheFileAndTheProblem) {
  const std::string ok_tail = R"("features": ["f1"], "weights": [1])";
  EXPECT_EQ(parse_model(R"({"metric": "x", )" + ok_tail + "}", "m.json").model.weights[0], 1.0);
  EXPECT_EQ(parse_error("{"), "m.json: model file: not valid JSON");
  EXPECT_EQ(parse_error("[1]"), "m.json: model file: the top level must be a JSON object");
  EXPECT_EQ(parse_error(R"({"metric": "x", "weight": [1], )" + ok_tail + "}"),
            "m.json: model file: unknown key \"weight\"");
  EXPECT_EQ(parse_error(R"({)" + ok_tail + "}"), "m.json: model file: missing \"metric\"");
  EXPECT_EQ(parse_error(R"({"metric": "x", "features": ["f9"], "weights": [1]})"),
            "m.json: model file: unknown feature \"f9\" (expected f1..f8)");
  EXPECT_EQ(parse_error(R"({"metric": "x", "features": ["f1", "F1"], "weights": [1, 2]})"),
            "m.json: model file: feature f1 listed twice");
  EXPECT_EQ(parse_error(R"({"metric": "x", "features": ["f1"], "weights": [1, 2]})"),
            "m.json: model file: \"features\" has 1 names but \"weights\" 2 numbers");
  EXPECT_EQ(parse_error(R"({"metric": "x", "features": ["f1"], "weights": ["1"]})"),
            "m.json: model file: weight of f1 must be a number");
  EXPECT_EQ(parse_error(R"({"metric": "x", "features": ["f1"], "weights": [0]})"),
            "m.json: model file: every weight is 0");
  EXPECT_EQ(parse_error(R"({"format": "other", "metric": "x", )" + ok_tail + "}"),
            "m.json: model file: \"format\" must be \"qm3d-model/1\"");
  EXPECT_EQ(parse_error(R"({"metric": "x", "logistic": {"beta1": 1}, )" + ok_tail + "}"),
            "m.json: model file: \"logistic\" lacks \"beta2\"");
}

TEST(ModelIo, FeatureNames) {
  EXPECT_EQ(feature_index("f1"), 0u);
  EXPECT_EQ(feature_index("F8"), 7u);
  EXPECT_EQ(feature_name(2), "f3");
  EXPECT_THROW(feature_index("f0"), FormatError);
  EXPECT_THROW(feature_index("f10"), FormatError);
  EXPECT_THROW(feature_index("g1"), FormatError);
}

}  // namespace
}  // namespace qm3d
