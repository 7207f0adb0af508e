// What the mesh module brings to a metric registry (qm3d/common/metric.h): CMDM and MSDM2, the
// mesh readers (OBJ, OFF, PLY; textured OBJ coloured from its texture), the surface sampler and
// the colour matcher (D_LAB's mesh side: CMDM's projection).
#pragma once

#include "qm3d/common/metric.h"

namespace qm3d::mesh {

/// CMDM's registry entry (cmdm.cpp): meshes with vertex colours; option `scales`; a model.
MetricSpec cmdm_spec();
/// MSDM2's registry entry (msdm2.cpp): meshes (colours ignored); option `scales`.
MetricSpec msdm2_spec();

/// D_LAB's mesh side (surface_colours.cpp): each vertex of `iterated` with its closest point on
/// `other`'s surface, found and coloured as CMDM does (its projection, the LAB2000HL colours of
/// the face's vertices interpolated with its Heron weights). FormatError naming the file for a
/// mesh without vertex colours. Registered as the registry's colour matcher.
SurfaceColours match_surface_colours(const Input& iterated, const Input& other,
                                     const Lab2000hlTable& table, int threads);

/// Registers the mesh readers, the surface sampler, the colour matcher, CMDM and MSDM2 (in that
/// order).
void register_metrics(Registry& registry);

}  // namespace qm3d::mesh
