// Fuzzes mmetric's grid sampling (qm3d/mesh/grid_sampling.h) on meshes read from OFF: the
// first byte picks the grid size (2..65) and the ray axes, the rest is the OFF file. Any
// coordinates the reader accepts must give samples or a typed error, never a crash.
#include <cstdint>
#include <new>
#include <stdexcept>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/mesh/grid_sampling.h"
#include "qm3d/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  qm3d::GridSamplingOptions o;
  o.grid_size = 2 + (data[0] & 63);
  o.all_axes = (data[0] & 64) != 0;
  o.threads = 1;
  try {
    const qm3d::mesh::MeshFile m =
        qm3d::mesh::parse_mesh(bytes, qm3d::mesh::MeshFormat::kOff, "fuzz", {false});
    qm3d::mesh::sample_grid(m.mesh, o);
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::bad_alloc&) {
  }
  return 0;
}
