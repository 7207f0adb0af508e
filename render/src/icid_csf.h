// iCID's image-appearance model 'iCAM_YCC' (the reference's FilterImageCSF with cpd 20,
// 'YCC-RIT', padding 'both', no XYZ clipping): contrast-sensitivity filtering in the frequency
// domain. Private to render/src.
#pragma once

#include <vector>

namespace qm3d::render::icid_detail {

/// XYZ planes of one image (rows x cols, row-major).
struct XyzPlanes {
  int rows = 0, cols = 0;
  std::vector<double> x, y, z;
};

/// Filters both images' XYZ planes in place (both of the same size), with `threads` OpenMP
/// threads (0 = OpenMP's default): the same bits for any count.
void csf_filter(XyzPlanes& a, XyzPlanes& b, int threads);

/// csf_filter through the full 3n-point transforms of every padded line (Eigen's kissfft), not
/// the pruned ones: the tests' check of the pruning.
void csf_filter_full_transforms(XyzPlanes& a, XyzPlanes& b, int threads);

}  // namespace qm3d::render::icid_detail
