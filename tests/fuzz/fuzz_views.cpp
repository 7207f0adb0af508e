// Fuzzes the view writer of `ibsm --save-views` (render/src/ibsm.cpp's write_png: png_bytes,
// then write_file_atomically) on fuzzed views: the first two bytes pick the width and height
// (0..127 each), the rest are the RGBA pixels (repeated to fill the view; none: all zero). A view
// must be written and read back (stb_image) pixel for pixel, rows bottom first in the view and
// top first in the PNG, or be refused with a typed error; never a crash, never a file left
// behind but the one written. The files go to a fresh directory under $TMPDIR, removed at exit.
#include <stb/stb_image.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/render/ibsm.h"
#include "qm3d/render/raster.h"

namespace {

namespace fs = std::filesystem;

struct Scratch {
  fs::path dir;
  Scratch() {
    std::string pattern = (fs::temp_directory_path() / "qm3d-fuzz-views-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) std::abort();
    dir = pattern;
  }
  ~Scratch() {
    std::error_code ignored;
    fs::remove_all(dir, ignored);
  }
};

const fs::path& scratch() {
  static const Scratch s;
  return s.dir;
}

qm3d::render::View fuzzed_view(const std::uint8_t* data, std::size_t size) {
  qm3d::render::View v;
  v.width = size > 0 ? data[0] & 127 : 0;
  v.height = size > 1 ? data[1] & 127 : 0;
  const std::size_t bytes = static_cast<std::size_t>(v.width) * v.height * 4;
  v.rgba.resize(bytes);
  v.depth.assign(bytes / 4, 0.0f);
  const std::size_t given = size > 2 ? size - 2 : 0;
  for (std::size_t i = 0; i < bytes && given > 0; ++i) v.rgba[i] = data[2 + i % given];
  return v;
}

// The PNG at `path` holds the view's pixels (its rows top first).
bool reads_back(const fs::path& path, const qm3d::render::View& v) {
  std::ifstream in(path, std::ios::binary);
  const std::string png((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()),
                                          static_cast<int>(png.size()), &w, &h, &channels, 4);
  bool same = pixels != nullptr && w == v.width && h == v.height;
  const std::size_t row = static_cast<std::size_t>(v.width) * 4;
  for (int y = 0; same && y < h; ++y) {
    const std::uint8_t* want = v.rgba.data() + row * static_cast<std::size_t>(h - 1 - y);
    same = std::equal(want, want + row, pixels + row * static_cast<std::size_t>(y));
  }
  stbi_image_free(pixels);
  return same;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const qm3d::render::View v = fuzzed_view(data, size);
  const fs::path path = scratch() / "view_00_reference.png";
  try {
    const std::vector<std::uint8_t> png = qm3d::render::png_bytes(v);
    qm3d::write_file_atomically(path, [&](std::ostream& out) {
      out.write(reinterpret_cast<const char*>(png.data()),
                static_cast<std::streamsize>(png.size()));
    });
    if (!reads_back(path, v)) __builtin_trap();  // a view lost or changed on its way to disk
  } catch (const qm3d::Error&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::bad_alloc&) {
  }
  // Nothing but the view's own file: no temporary left behind.
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(scratch())) files += e.path() != path;
  if (files != 0) __builtin_trap();
  return 0;
}
