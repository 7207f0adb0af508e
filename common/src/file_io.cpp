#include "qm3d/common/file_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

#include "qm3d/common/error.h"

namespace qm3d {

std::string read_file_bytes(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(path.string() + ": no such file");
  if (fs::is_directory(status)) throw InputError(path.string() + ": is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(path.string() + ": cannot open for reading (" + std::strerror(errno) + ")");
  }
  const auto size = fs::file_size(path, ec);
  if (!ec && size > max_bytes) {
    throw InputError(path.string() + ": file too large (" + std::to_string(size) + " bytes)");
  }
  std::string bytes;
  if (!ec) {
    // Regular file of known size: one allocation, no intermediate copy.
    bytes.resize(static_cast<std::size_t>(size));
    in.read(bytes.data(), static_cast<std::streamsize>(size));
    if (in.gcount() != static_cast<std::streamsize>(size)) {
      throw InputError(path.string() + ": read error (file changed while reading?)");
    }
  } else {
    std::ostringstream buffer;  // e.g. a pipe: size unknown
    buffer << in.rdbuf();
    bytes = buffer.str();
  }
  if (in.bad()) throw InputError(path.string() + ": read error");
  return bytes;
}

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  std::random_device rd;
  const fs::path tmp =
      path.string() + ".tmp-" + std::to_string(static_cast<unsigned long>(rd()) % 1000000);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw InputError(path.string() + ": cannot write (" + std::strerror(errno) + ")");
    }
    try {
      write(out);
      out.flush();
    } catch (...) {
      out.close();
      std::error_code ec;
      fs::remove(tmp, ec);
      throw;
    }
    if (!out) {
      out.close();
      std::error_code ec;
      fs::remove(tmp, ec);
      throw InputError(path.string() + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(path.string() + ": cannot write (" + ec.message() + ")");
  }
}

std::filesystem::path installed_share_dir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return {};
  const std::filesystem::path share = exe.parent_path().parent_path() / "share" / "qm3d";
  return std::filesystem::is_directory(share, ec) ? share : std::filesystem::path();
}

}  // namespace qm3d
