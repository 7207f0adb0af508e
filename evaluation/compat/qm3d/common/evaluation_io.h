// Deprecated: moved to qm3d/evaluation/evaluation_io.h (target qm3d::evaluation, namespace
// qm3d::evaluation). This header forwards there for one release (0.1.x) and will then be removed;
// the names stay visible in namespace qm3d meanwhile. docs/library.md lists the new paths.
#pragma once

#if defined(__GNUC__) && !defined(__clang__)
// A note, not a warning: builds with -Werror keep working.
#pragma message("qm3d/common/evaluation_io.h is deprecated: include qm3d/evaluation/evaluation_io.h (namespace qm3d::evaluation)")
#endif

#include "qm3d/evaluation/evaluation_io.h"

namespace qm3d {
using namespace qm3d::evaluation;  // NOLINT(google-build-using-namespace): the old names, one release
}  // namespace qm3d
