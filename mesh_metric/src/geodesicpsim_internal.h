// GeodesicPSIM's engine (qm3d/mesh/geodesicpsim.h), internal: the meshes as its reference holds
// them, their cleaning and subdivision, and the features of one keypoint's patches.
//
// Reference: Qi-Yangsjtu/GeodesicPSIM @ 3e06453 (no licence: implemented from the paper, Yang et
// al., arXiv:2308.04928, and the rules of docs SPEC-GEODESICPSIM.md; nothing copied).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace qm3d::mesh::gpsim {

using P3 = std::array<double, 3>;
using P2 = std::array<double, 2>;
using Tri = std::array<int, 3>;

/// A triangle mesh with one UV per face corner, as the reference reads and cleans it.
struct GpMesh {
  std::vector<P3> v;    ///< positions (float32 values widened to double)
  std::vector<P2> uv;   ///< texture coordinates
  std::vector<Tri> f;   ///< vertex indices of each face
  std::vector<Tri> ft;  ///< UV indices of each face's corners
};

/// An 8-bit RGB image, row 0 the top row of the file, texels row-major.
struct GpTexture {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 bytes per texel
};

/// The OBJ's `v`, `vt` and `f a/t[/n]` lines as the reference reads them: every number through
/// std::stof (float32) then widened. FormatError naming `name` for what it cannot read
/// (non-triangles, corners without UV, indices out of range, no faces, no UVs).
GpMesh read_obj_as_reference(const std::string& text, const std::string& name);

/// A texture image decoded to 8-bit RGB (stb), as the reference's OpenCV imread(path,
/// IMREAD_COLOR) reads a PNG. InputError / FormatError naming the file when it is missing or
/// cannot be decoded.
GpTexture read_texture_8bit(const std::filesystem::path& file);

/// The reference's cleaning: single UV wrap, unreferenced vertices / UVs dropped, equal positions
/// and UVs merged, degenerate and duplicate faces dropped (SPEC step 2).
GpMesh clean_mesh(GpMesh m);

/// Which mesh was subdivided to equalise face counts (SPEC step 4).
enum class Subdivided { kNone = 0, kReference = 1, kDistorted = 2 };

/// Subdivides the mesh with fewer faces toward the other's face count, then cleans it.
Subdivided equalise_face_counts(GpMesh& reference, GpMesh& distorted);

/// Deterministic farthest-point keypoints of `vertices`: the first is vertex 0, each next the
/// farthest from those chosen (ties to the lowest index); `threads` OpenMP threads (> 0).
std::vector<P3> farthest_points(const std::vector<P3>& vertices, int count, int threads);

/// Nearest vertex search with the reference's tie rule (lowest index among equal distances).
class NearestVertex {
 public:
  explicit NearestVertex(const std::vector<P3>& points);
  /// The nearest vertex and its distance (computed as the reference computes it).
  int nearest(const P3& q, double& distance) const;

 private:
  struct Node {
    int begin, end;  // range of order_
    int left = -1, right = -1;
    int axis = -1;  // -1: leaf
    double split = 0;
  };
  int build(int begin, int end);
  void search(int node, const P3& q, double& best_d, int& best_i) const;
  const std::vector<P3>& points_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

/// A mesh with what the patches need: faces around each vertex (ascending face order).
struct PatchSource {
  const GpMesh* mesh = nullptr;
  const GpTexture* texture = nullptr;
  std::vector<int> face_offsets;  ///< vertex v: faces [offsets[v], offsets[v+1]) of faces_
  std::vector<int> faces;
  NearestVertex* nearest = nullptr;
};

/// The six texel statistics of a patch (Y, U, V mean and variance), npix-weighted over faces.
struct TexelStats {
  double lm = 0, lvar = 0, c1m = 0, c1var = 0, c2m = 0, c2var = 0;
};

/// What one keypoint contributes (the reference's per-patch values).
struct KeypointValues {
  int flag = 0;  ///< 0 skipped (a patch of <= 3 vertices), 1, 2, 3 (SPEC step 7)
  double center_shift = 0;
  double patch_size = 0;
  int ref_npix = 0, dis_npix = 0;
  std::array<double, 3> ref_smooth{}, dis_smooth{};
  double ref_cur = 0, dis_cur = 0;
  TexelStats ref_stats, dis_stats;
};

/// The per-patch values of one keypoint (SPEC steps 6-8); `threshold` = 0.0005 x the largest
/// side of the reference's box.
KeypointValues keypoint_values(const PatchSource& ref, const PatchSource& dis, const P3& keypoint,
                               double threshold);

}  // namespace qm3d::mesh::gpsim
