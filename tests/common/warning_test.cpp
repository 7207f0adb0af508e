// The warning builder (warning.h): one line of at most kMaxWarningLine characters, the rest in
// the details (issue 44 item 2).
#include "qm3d/common/warning.h"

#include <gtest/gtest.h>

#include <string>

#include "qm3d/common/result.h"

namespace qm3d {
namespace {

TEST(Warning, AShortWarningIsSubjectCauseAndRemedyOnOneLine) {
  const Warning w = make_warning("a.ply", "3 points have no colour", "give colours");
  EXPECT_EQ(w.line, "a.ply: 3 points have no colour; give colours");
  EXPECT_TRUE(w.details.empty());
  EXPECT_EQ(make_warning("", "cause").line, "cause");
}

TEST(Warning, ALongPathIsShortenedToItsFileNameAndKeptInTheDetails) {
  const std::string dir = "/data/" + std::string(150, 'd') + "/";
  const Warning w = make_warning(dir + "mesh.off", "12 faces repeat a vertex", "dropped");
  EXPECT_EQ(w.line, "mesh.off: 12 faces repeat a vertex; dropped");
  EXPECT_NE(w.details.find(dir + "mesh.off"), std::string::npos);
}

TEST(Warning, AVeryLongFileNameKeepsItsEnd) {
  const std::string name = std::string(300, 'n') + "_end.ply";
  const Warning w = make_warning(name, "the cause", "the remedy");
  EXPECT_LE(w.line.size(), kMaxWarningLine);
  EXPECT_EQ(w.line.substr(0, 3), "...");
  EXPECT_NE(w.line.find("_end.ply: the cause; the remedy"), std::string::npos);
  EXPECT_NE(w.details.find(name), std::string::npos);
}

TEST(Warning, AnOverlongCauseIsCutAtAWordWithTheWholeTextInTheDetails) {
  std::string cause;
  for (int i = 0; i < 40; ++i) cause += "word" + std::to_string(i) + " ";
  const Warning w = make_warning("PCQM", cause, "the remedy");
  EXPECT_LE(w.line.size(), kMaxWarningLine);
  EXPECT_NE(w.line.find(kWarningCut), std::string::npos);
  const std::string kept = w.line.substr(0, w.line.size() - std::string(kWarningCut).size());
  EXPECT_EQ(kept.back() != ' ', true);
  EXPECT_NE(w.details.find("the remedy"), std::string::npos);
  EXPECT_NE(w.details.find(kept), std::string::npos);
}

TEST(Warning, FitWarningReplacesTheInputsPathsByTheirNames) {
  const std::string path = "/very/" + std::string(140, 'p') + "/ref.ply";
  const Warning w = fit_warning(path + ": 2 duplicate points", {path});
  EXPECT_EQ(w.line, "ref.ply: 2 duplicate points");
  EXPECT_EQ(w.details, path + ": 2 duplicate points");
  const Warning short_one = fit_warning("x: fine", {"x"});
  EXPECT_EQ(short_one.line, "x: fine");
  EXPECT_TRUE(short_one.details.empty());
}

TEST(Warning, AddWarningKeepsEachLineOnceWithItsDetails) {
  MetricResult r;
  add_warning(r, {"line one", "more"});
  add_warning(r, {"line one", "more"});
  add_warning(r, {"line two", ""});
  ASSERT_EQ(r.warnings.size(), 2u);
  ASSERT_EQ(r.warning_details.size(), 1u);
  EXPECT_EQ(r.warning_details[0].warning, "line one");
  EXPECT_EQ(r.warning_details[0].details, "more");
}

TEST(Warning, FitWarningsShortensEveryLineOfAResult) {
  MetricResult r;
  const std::string path = "/" + std::string(200, 'q') + "/d.off";
  r.warnings = {path + ": dropped 3 vertices that no face uses", "short"};
  fit_warnings(r, {path});
  EXPECT_EQ(r.warnings[0], "d.off: dropped 3 vertices that no face uses");
  EXPECT_EQ(r.warnings[1], "short");
  ASSERT_EQ(r.warning_details.size(), 1u);
  EXPECT_EQ(r.warning_details[0].warning, r.warnings[0]);
  EXPECT_NE(r.warning_details[0].details.find(path), std::string::npos);
}

}  // namespace
}  // namespace qm3d
