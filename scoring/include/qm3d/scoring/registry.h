// The registry of every metric qm3d ships: the one list the tool, batch, the report and Python
// all read (the registry mechanism itself is common/'s metric.h).
#pragma once

#include "qm3d/common/metric.h"

namespace qm3d::scoring {

/// Every registered metric, in registration order: the mesh module's, the point-cloud module's,
/// then the renderer's (the order `compare` runs them and `qm3d --help` lists them). Built once,
/// on first use; thread-safe.
const Registry& default_registry();

}  // namespace qm3d::scoring
