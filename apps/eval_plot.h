// The scatter plot of `qm3d eval --plot`: objective score against MOS with the fitted logistic.
// SVG is written directly; PNG is drawn by gnuplot (Debian package gnuplot-nox), run as a child
// process, and is an error naming the missing program when gnuplot is not installed.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "qm3d/common/evaluation.h"

namespace qm3d::app {

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

/// Writes the AUC figure as SVG (atomically): per metric a bar for AUC_DS and one for AUC_BW,
/// each with its 95 % DeLong interval (AUC +- 1.96 SE), on a 0.5 (chance) to 1 axis.
void write_auc_plot(const std::filesystem::path& path, const AucPlot& plot);

/// Writes `plot` to `path` (atomically): `.svg` directly, `.png` through gnuplot.
/// @throws InputError  another extension, gnuplot missing (for PNG) or failing, write errors
void write_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot);

}  // namespace qm3d::app
