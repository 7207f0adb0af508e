// GraphSIM (Yang, Ma, Xu, Li, Sun, "Inferring point cloud quality via graph similarity", IEEE
// TPAMI 2020) and MS-GraphSIM (Zhang, Yang, Xu, "MS-GraphSIM: inferring point cloud quality via
// multiscale graph similarity", ACM MM 2021): the per-keypoint engine. Written from the papers and
// the rules of docs SPEC-GRAPHSIM.md / the reference data's README (NJUVISION/GraphSIM @ fdd595d,
// zhangyujie-1998/MS_GraphSIM @ b225a59 run in float64); every rule that decides a number is
// stated where it is applied, in graphsim_engine.cpp.
//
// For a keypoint c of the reference (with its reference colour q) and each cloud X in {R, D}:
//   local set  P  = {(c, q)} and the points of X with 0 < |p - c| <= eps, unique, sorted;
//   graph radius rho = the largest 50th-nearest distance within P over 100 sampled rows;
//   graph rows P' = (c, q) and the rows of P with 0 < |p - c| <= rho, weights exp(-d^2/(rho^2/2));
//   colour gradient moments of P'_R and P'_D (LMN colour space) compared channel by channel.
// MS-GraphSIM blurs the colours on a radius graph of P', samples every other row and shrinks the
// coordinates towards c, five times, and scores each scale alike.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "kd_tree.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// A colour as the reference holds it: 0..255 per channel (8-bit values, blurred ones fractional).
using Colour255 = std::array<double, 3>;

/// One cloud ready for the local searches: positions, colours 0..255, and its k-d tree.
struct GraphsimCloud {
  GraphsimCloud(std::vector<Vec3> positions, std::vector<Colour255> colours, int threads);
  std::vector<Vec3> positions;
  std::vector<Colour255> colours;
  KdTree tree;
};

/// The parameters of one run (the metrics' options).
struct GraphsimParams {
  double threshold = 0.001;                ///< T of the mg / mug similarity
  std::array<double, 3> weights{6, 1, 1};  ///< pooling weights of the L, M, N channels
  double blur_ratio = 0.5;                 ///< r_b: the blur graph's radius = r_b * rho
  double sample_ratio = 1.0 / 3.0;         ///< r_s: coordinates shrink by 0.5^r_s per scale
  int scales = 1;                          ///< scales computed (1 = GraphSIM)
};

/// The score of one keypoint at each scale, and the channel products |p_L|, |p_M|, |p_N| of
/// scale 0.
struct KeypointScores {
  std::vector<double> per_scale;
  std::array<double, 3> channels{};
  /// The reference's scale-0 graph has at most one point besides the keypoint: cg, hence the
  /// score, is 0 whatever the distorted cloud (the reference's rule; a cloud sparse at eps).
  bool lone = false;
};

/// Scores one keypoint (row `keypoint` of the reference) at params.scales scales; `eps` is the
/// neighbourhood radius (floor of the reference's smallest box side / 10).
KeypointScores score_keypoint(const GraphsimCloud& reference, const GraphsimCloud& distorted,
                              std::size_t keypoint, double eps, const GraphsimParams& params);

/// Chooses `count` keypoints (rows of `positions`, drawn with replacement) by qm3d's seeded rule
/// (graphsim_keypoints.cpp): each point's local variation score, as the authors' keypoint script
/// computes it, as the sampling weight, and a 64-bit Mersenne Twister seeded with `seed`.
std::vector<std::size_t> choose_keypoints(const std::vector<Vec3>& positions, std::size_t count,
                                          std::uint64_t seed, int threads);

}  // namespace qm3d::pointcloud::detail
