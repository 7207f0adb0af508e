// What the mesh module brings to a metric registry (qm3d/common/metric.h): CMDM and MSDM2, the
// mesh readers (OBJ, OFF, PLY; textured OBJ coloured from its texture) and the surface sampler.
#pragma once

#include "qm3d/common/metric.h"

namespace qm3d::mesh {

/// CMDM's registry entry (cmdm.cpp): meshes with vertex colours; option `scales`; a model.
MetricSpec cmdm_spec();
/// MSDM2's registry entry (msdm2.cpp): meshes (colours ignored); option `scales`.
MetricSpec msdm2_spec();

/// Registers the mesh readers, the surface sampler, CMDM and MSDM2 (in that order).
void register_metrics(Registry& registry);

}  // namespace qm3d::mesh
