// Small file helpers shared by the readers and writers: bounded whole-file reads with clear
// errors (regular files and pipes; devices and sockets refused), writes that never leave a
// partial file behind nor replace a FIFO, a device or a symlink, and the checks a command makes
// on its output paths before a long computation.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace qm3d {

/// Size limits of the files qm3d reads. A regular file larger than its limit is refused before
/// anything is read; a pipe is read until its end or the limit, whichever comes first.
/// Meshes and clouds: a 16 GiB file is ~500 M vertices, beyond what fits in memory once read.
inline constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t(16) << 30;
/// CSV tables (batch lists, results, MOS and score tables): 1 GiB is ~10 M rows of paths.
inline constexpr std::uintmax_t kMaxTableBytes = std::uintmax_t(1) << 30;
/// MTL material libraries: a few lines per material; 64 MiB is ~1 M materials.
inline constexpr std::uintmax_t kMaxMtlBytes = std::uintmax_t(64) << 20;
/// Texture images (PNG, JPEG ...): 1 GiB holds an uncompressed 16384 x 16384 RGBA image.
inline constexpr std::uintmax_t kMaxTextureBytes = std::uintmax_t(1) << 30;
/// How long a pipe may stay without data (e.g. a FIFO that no program writes) before a read
/// gives up with an error instead of waiting forever.
inline constexpr std::chrono::milliseconds kPipeIdleWait{30000};

/// The content of a regular file or of a pipe (a FIFO, `<(zcat a.ply.gz)`, /dev/stdin on a
/// pipe). Throws InputError naming the file when it does not exist, is a directory, a device
/// or a socket ("not a regular file (character device)"), cannot be read, is larger than
/// `max_bytes`, or is a pipe that gives no data for `pipe_idle_wait`.
std::string read_file_bytes(const std::filesystem::path& path,
                            std::uintmax_t max_bytes = kMaxInputBytes,
                            std::chrono::milliseconds pipe_idle_wait = kPipeIdleWait);

/// "regular file", "directory", "FIFO", "character device", "block device", "socket",
/// "symlink" (dangling), "missing" or "special file": what `path` is, symlinks followed.
std::string file_kind(const std::filesystem::path& path);

/// The extension of `path` in lower case, without the dot ("ply", "off", ...).
std::string lower_extension(const std::filesystem::path& path);

/// Writes a file through `write`, never leaving a partial file behind. A regular file (or a new
/// path) is written to a temporary file beside it (created with O_EXCL | O_NOFOLLOW), renamed
/// over it only when everything was written; a symlink is followed and its target replaced so
/// (the link is kept). A FIFO, a device (/dev/null ...) and the standard streams (/dev/stdout,
/// /dev/stderr, /dev/fd/N, /proc/self/fd/N) are written into directly, never replaced. On any
/// failure (disk full, a closed pipe) the temporary file is removed and InputError names `path`.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

/// A file a command reads or writes, with the option that names it ("-o", "--map", "REF" ...).
struct NamedPath {
  std::string option;
  std::filesystem::path path;
};

/// True when writing `b` would replace `a`: the same regular file by identity (hard links and
/// symlinks included) or the same new path. FIFOs, devices and standard streams are never the
/// same (writing into them replaces nothing). The rule check_outputs applies.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// Checks, before any long computation, that each output can be written: its folder exists and
/// takes new files, it is not a directory, and it is neither one of `inputs` nor another output
/// (the same file by identity, hard links and symlinks included, or the same new path). Outputs
/// with an empty path are skipped; FIFOs, devices and standard streams may be shared. Throws
/// InputError "OPTION PATH: problem".
void check_outputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

/// PREFIX/share/qm3d when the running program is PREFIX/bin/<program> of an installed qm3d
/// (that directory exists); empty otherwise (a build tree, or a program installed elsewhere).
std::filesystem::path installed_share_dir();

}  // namespace qm3d
