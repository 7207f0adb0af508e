// Fuzzes the PLY reader: any bytes must give content or a qm3d::Error, nothing else.
#include <cstdint>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    qm3d::ply::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  } catch (const qm3d::Error&) {
  }
  return 0;
}
