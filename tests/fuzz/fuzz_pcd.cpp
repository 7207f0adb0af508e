// Fuzzes the PCD reader (PCL reads from a path, so each input goes through a temporary file).
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/pointcloud/cloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("qm3d_fuzz_" + std::to_string(::getpid()) + ".pcd");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    qm3d::pointcloud::read_cloud(path);
  } catch (const qm3d::Error&) {
  }
  return 0;
}
