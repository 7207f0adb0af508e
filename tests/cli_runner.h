// Runs the built `qm3d` binary for the end-to-end tests. QM3D_BINARY is set by CMake.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace qm3d::test {

struct CliRun {
  int code = -1;  ///< exit code (-1: killed by a signal)
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `qm3d ARGS` (ARGS is shell text; `env` e.g. "PATH=/none" goes before it) in `cwd`,
/// capturing stdout and stderr through files in `io_dir`, under a 120 s time limit.
inline CliRun run_qm3d(const std::string& args, const std::filesystem::path& cwd,
                       const std::filesystem::path& io_dir, const std::string& env = "") {
  const auto out = io_dir / "stdout", err = io_dir / "stderr";
  const std::string cmd = "cd '" + cwd.string() + "' && " + env + " /usr/bin/timeout 120 '" + QM3D_BINARY + "' " +
                          args + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  return CliRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace qm3d::test
