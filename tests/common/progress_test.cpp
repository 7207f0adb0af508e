#include "qm3d/common/progress.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <thread>

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

// Issue 44 item 6: a stage reports from inside its loop, within its own share of the whole.
TEST_F(ProgressStepsTest, WithinReportsTheStagesShareNeverDecreasing) {
  ProgressSteps steps(callback_, 4);
  steps.begin("a");
  steps.begin("b", 2);
  steps.within(0.5);
  steps.within(0.25);  // never back
  steps.within(2.0);   // clamped to the stage's end
  steps.begin("c");
  EXPECT_EQ(calls_,
            (Calls{{"a", 0.0}, {"b", 0.25}, {"b", 0.5}, {"b", 0.5}, {"b", 0.75}, {"c", 0.75}}));
}

TEST_F(ProgressStepsTest, LoopProgressReportsEachHundredthFromItsOwnThreadOnly) {
  ProgressSteps steps(callback_, 2);
  steps.begin("loop");
  {
    LoopProgress loop(&steps, 1000);
    std::thread other([&] {
      for (int i = 0; i < 500; ++i) loop.add();  // counted, never reported from here
    });
    other.join();
    ASSERT_EQ(calls_.size(), 1u);
    for (int i = 0; i < 500; ++i) loop.add();
  }
  // The first add of the owner already sees half the work: 50 hundredths, then one each.
  ASSERT_GE(calls_.size(), 1u + 50u);
  EXPECT_LE(calls_.size(), 1u + 101u);
  for (std::size_t i = 1; i < calls_.size(); ++i) {
    EXPECT_EQ(calls_[i].first, "loop");
    EXPECT_LE(calls_[i - 1].second, calls_[i].second);
  }
  EXPECT_DOUBLE_EQ(calls_.back().second, 0.5);  // the stage's whole share, not more
}

// A callback that throws (a cancelled call) never throws out of the loop: finish() rethrows.
TEST(LoopProgress, WhatTheCallbackThrowsComesOutOfFinish) {
  ProgressSteps steps([](const std::string&, double f) {
    if (f > 0) throw std::runtime_error("cancelled");
  }, 1);
  steps.begin("loop");
  LoopProgress loop(&steps, 10);
  for (int i = 0; i < 10; ++i) EXPECT_NO_THROW(loop.add());
  EXPECT_THROW(loop.finish(), std::runtime_error);
  EXPECT_NO_THROW(loop.finish());  // once
}

TEST(LoopProgress, WithoutAListenerItOnlyCounts) {
  LoopProgress none(nullptr, 10);
  none.add(5);
  ProgressSteps silent(ProgressCallback{}, 1);
  LoopProgress quiet(&silent, 10);
  quiet.add(10);  // would throw std::bad_function_call if it called the empty callback
}

}  // namespace
}  // namespace qm3d
