// Fuzzes CMDM, MSDM2, PCQM and pc_error's PSNR on tiny meshes built from the input bytes: up to 10 vertices with
// small integer coordinates (so coincident points, zero-area and non-manifold faces are common),
// colours, and up to 12 faces. Any outcome but a qm3d::Error or std::invalid_argument is a bug.
#include <cstdint>
#include <stdexcept>

#include "qm3d/common/error.h"
#include "qm3d/common/types.h"
#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/msdm2.h"
#include "qm3d/pointcloud/pcqm.h"
#include "qm3d/pointcloud/psnr.h"

namespace {

struct Bytes {
  const std::uint8_t* data;
  std::size_t size, pos = 0;
  std::uint8_t next() { return pos < size ? data[pos++] : 0; }
};

qm3d::ColoredMesh tiny_mesh(Bytes& in) {
  qm3d::ColoredMesh m;
  const int n = 3 + in.next() % 8;
  for (int i = 0; i < n; ++i) {
    m.positions.push_back({(in.next() % 9) / 4.0, (in.next() % 9) / 4.0, (in.next() % 9) / 4.0});
    m.colors.push_back({in.next() / 255.0, in.next() / 255.0, in.next() / 255.0});
  }
  const int faces = 1 + in.next() % 12;
  for (int f = 0; f < faces; ++f) {
    m.triangles.push_back({static_cast<std::uint32_t>(in.next() % n),
                           static_cast<std::uint32_t>(in.next() % n),
                           static_cast<std::uint32_t>(in.next() % n)});
  }
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  const qm3d::ColoredMesh a = tiny_mesh(in), b = tiny_mesh(in);
  try {
    qm3d::mesh::CmdmOptions c;
    c.data_dir = QM3D_FUZZ_TABLES;
    c.scales = 1 + in.next() % 3;
    qm3d::mesh::compute_cmdm(a, b, c);
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  }
  try {
    qm3d::mesh::Msdm2Options m;
    m.direction = qm3d::Direction::kSymmetric;
    m.scales = 2;
    qm3d::mesh::compute_msdm2(a, b, m);
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  }
  try {
    qm3d::pointcloud::PcqmOptions p;
    p.data_dir = QM3D_FUZZ_TABLES;
    p.radius_rel = 0.05 + (in.next() % 8) / 10.0;
    p.knn = 1 + in.next() % 6;
    p.direction = qm3d::Direction::kSymmetric;
    qm3d::pointcloud::compute_pcqm(qm3d::vertex_cloud(a), qm3d::vertex_cloud(b), p);
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  }
  // PSNR on the vertices: coincident points (duplicate merging, the tie chain), the automatic
  // peak of clouds with no two distinct points, estimated or fuzzed normals (zero ones included).
  try {
    namespace pc = qm3d::pointcloud;
    pc::PsnrOptions o;
    o.colour_space = static_cast<pc::PsnrColourSpace>(in.next() % 3);
    o.duplicates = static_cast<pc::DuplicatePoints>(in.next() % 3);
    o.tied = static_cast<pc::TiedNeighbours>(1 + in.next() % 2);
    o.average_normals = in.next() % 2 == 0;
    o.estimate_normals = in.next() % 4 == 0;
    if (in.next() % 2) o.peak = 1 + in.next() % 1023;
    const qm3d::ColoredCloud ca = qm3d::vertex_cloud(a);
    pc::ReferenceNormals normals;
    if (!o.estimate_normals && in.next() % 2) {
      for (std::size_t i = 0; i < ca.positions.size(); ++i) {
        normals.normals.push_back({(in.next() % 3) - 1.0, (in.next() % 3) - 1.0, (in.next() % 3) - 1.0});
      }
    }
    pc::compute_psnr(ca, normals, qm3d::vertex_cloud(b), o, "a", "b");
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
