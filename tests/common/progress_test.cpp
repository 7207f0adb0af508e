#include "qm3d/common/progress.h"

#include <gtest/gtest.h>

#include "progress_recorder.h"

namespace qm3d {
namespace {

using Calls = test::ProgressCalls;

class ProgressStepsTest : public ::testing::Test {
 protected:
  test::ProgressRecorder recorder_;
  const ProgressCallback callback_ = recorder_.callback();
  const Calls& calls_ = recorder_.calls;
};

TEST_F(ProgressStepsTest, ReportsTheStepsDoneWhenEachStageStarts) {
  ProgressSteps steps(callback_, 4);
  steps.begin("a");
  steps.begin("b", 2);
  steps.begin("c");
  steps.finish();
  EXPECT_EQ(calls_, (Calls{{"a", 0.0}, {"b", 0.25}, {"c", 0.75}, {"done", 1.0}}));
}

TEST_F(ProgressStepsTest, NeverReportsMoreThanTheWholeWhenStagesOverrun) {
  ProgressSteps steps(callback_, 1);
  steps.begin("a");
  steps.begin("b");
  steps.begin("c");
  ASSERT_EQ(calls_.size(), 3u);
  EXPECT_EQ(calls_[1].second, 1.0);
  EXPECT_EQ(calls_[2].second, 1.0);
}

TEST(ProgressSteps, AnEmptyCallbackIsNotCalled) {
  const ProgressCallback none;
  ProgressSteps steps(none, 3);
  steps.begin("a");  // would throw std::bad_function_call if called
  steps.finish();
}

}  // namespace
}  // namespace qm3d
