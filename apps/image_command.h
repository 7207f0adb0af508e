// `qm3d image A B`: iCID (render/icid.h), SSIM, MS-SSIM and PSNR of two 8-bit PNG / JPEG images.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace qm3d::app {

/// What `image` parses into.
struct ImageCommand {
  CLI::App* cmd = nullptr;
  std::string a, b;
  std::string intent = "perceptual";
  bool no_iam = false, omit_maps67 = false, no_downsampling = false;
  bool json = false, csv = false;
  std::string output;  ///< -o (empty = stdout)
  std::string map;     ///< --map FILE.npy: the per-pixel iCID map
};

/// Registers `image`; `add_common` adds --threads, --quiet, --data-dir.
std::unique_ptr<ImageCommand> add_image_command(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common);

/// Runs it when it was parsed (its exit code), else nullopt.
std::optional<int> run_image_command(const ImageCommand& c, int threads,
                                     const std::string& data_dir);

}  // namespace qm3d::app
