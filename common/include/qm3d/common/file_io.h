// Small file helpers shared by the readers and writers: whole-file reads with clear errors, and
// writes that never leave a partial file behind.
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

namespace qm3d {

/// The whole content of a regular file. Throws InputError naming the file when it does not
/// exist, is a directory, cannot be read, or is larger than `max_bytes`.
std::string read_file_bytes(const std::filesystem::path& path,
                            std::uintmax_t max_bytes = std::uintmax_t(16) << 30);

/// The extension of `path` in lower case, without the dot ("ply", "off", ...).
std::string lower_extension(const std::filesystem::path& path);

/// Writes a file atomically: `write` fills a stream that goes to a temporary file beside `path`,
/// which is renamed over `path` only when everything was written and flushed. On any failure the
/// temporary file is removed and InputError names `path`.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

/// PREFIX/share/qm3d when the running program is PREFIX/bin/<program> of an installed qm3d
/// (that directory exists); empty otherwise (a build tree, or a program installed elsewhere).
std::filesystem::path installed_share_dir();

}  // namespace qm3d
