// What the point-cloud module brings to a metric registry (qm3d/common/metric.h): PCQM (any two
// inputs, meshes read as their vertices), PCQM on surface samples of two meshes, pc_error's PSNR,
// D_LAB (any two inputs; two meshes through the mesh module's colour matcher) and the cloud
// readers (PLY, PCD).
#pragma once

#include "qm3d/common/metric.h"

namespace qm3d::pointcloud {

/// PCQM's registry entry (pcqm.cpp): options radius, knn, rx, bbox; a model.
MetricSpec pcqm_spec();
/// "pcqm_sampled" (pcqm_sampled.cpp): PCQM on clouds sampled from both meshes alike by
/// `sample` (the mesh module's sampler); PCQM's options plus points, density, seed.
MetricSpec pcqm_sampled_spec(SurfaceSampler sample);

/// "psnr" (psnr.cpp): MPEG pc_error's D1/D2/colour values of two clouds, or mmetric's of two meshes
/// sampled on one grid by `grid_sampler` (qm3d/pointcloud/psnr.h).
MetricSpec psnr_spec(GridSampler grid_sampler = {});

/// "dlab" (dlab.cpp): D_LAB, the mean LAB2000HL colour distance between each element and its
/// correspondence on the other object; two meshes by `on_surfaces` (the mesh module's colour
/// matcher: CMDM's projection) when given, any other pair (or every pair without it) by PCQM's
/// nearest neighbour, meshes read as their vertices. No options.
MetricSpec dlab_spec(SurfaceColourMatcher on_surfaces);

/// "graphsim" and "msgraphsim" (graphsim.cpp): GraphSIM and MS-GraphSIM of two coloured clouds
/// on keypoints of the reference (a keypoint file or qm3d's seeded draw); similarities.
MetricSpec graphsim_spec();
MetricSpec msgraphsim_spec();

/// "pointssim" (pointssim.cpp): PointSSIM of two clouds (meshes by their vertices), the numbers
/// of mmspg/pointssim (qm3d/pointcloud/pointssim.h); options neighbours, fit_knn, fit_radius,
/// estimators, poolings, attributes. Run by compare only when asked for.
MetricSpec pointssim_spec();

/// Samples drawn from each mesh by pcqm_sampled when no points / density is given.
inline constexpr int kDefaultSampledPoints = 20000;

/// Registers the cloud reader, PCQM, when a surface sampler is registered (the mesh module,
/// registered first) pcqm_sampled, psnr, dlab (with the registry's colour matcher), graphsim,
/// msgraphsim and pointssim.
void register_metrics(Registry& registry);

}  // namespace qm3d::pointcloud
