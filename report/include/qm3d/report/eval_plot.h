// The figures of `qm3d eval --plot`: objective score against MOS with the fitted mapping, and
// Krasula's AUCs. Each is one description (plot_canvas.h) written as SVG or rasterised to PNG.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "qm3d/evaluation/evaluation.h"

namespace qm3d::report {

struct ScatterPlot {
  std::vector<double> x;   ///< #n scores
  std::vector<double> y;   ///< #n MOS
  std::function<double(double)> curve;  ///< the fitted mapping, drawn over the range of x
  std::string title;
  std::string x_label;
  std::string y_label;
};

/// Krasula's AUCs of several metrics, for the summary figure of `qm3d eval --plot`.
struct AucPlot {
  std::vector<std::string> names;
  std::vector<double> auc_ds, se_ds, auc_bw, se_bw;  ///< NaN AUC_DS: no similar pairs
  std::string title;
};

/// Writes the AUC figure (atomically; .svg or .png): per metric a bar for AUC_DS and one for
/// AUC_BW, each with its 95 % DeLong interval (AUC +- 1.96 SE), on an axis from 0.5 (chance), or
/// lower when a bar or interval starts lower, to 1.
void write_auc_plot(const std::filesystem::path& path, const AucPlot& plot);

/// Writes `plot` to `path` (atomically): `.svg` or `.png`.
/// @throws InputError  another extension, write errors
void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot);

}  // namespace qm3d::report
