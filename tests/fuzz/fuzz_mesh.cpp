// Fuzzes the mesh readers (OBJ, OFF, PLY): the first byte picks the format.
#include <cstdint>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto format = static_cast<qm3d::mesh::MeshFormat>(data[0] % 3);
  const std::string bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    qm3d::mesh::parse_mesh(bytes, format, "fuzz", {/*require_colors=*/(data[0] & 4) != 0});
  } catch (const qm3d::Error&) {
  }
  return 0;
}
