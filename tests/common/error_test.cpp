#include "qm3d/common/error.h"

#include <gtest/gtest.h>

namespace qm3d {
namespace {

TEST(Error, KindsShareOneBaseAndKeepTheirMessage) {
  try {
    throw FormatError("a.ply: PLY: no end_header line");
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "a.ply: PLY: no end_header line");
  }
  EXPECT_THROW(throw InputError("x"), Error);
  EXPECT_THROW(throw NumericError("x"), Error);
  EXPECT_THROW(throw FormatError("x"), std::runtime_error);
}

}  // namespace
}  // namespace qm3d
