#include "qm3d/pointcloud/metrics.h"

#include "qm3d/common/error.h"
#include "qm3d/pointcloud/cloud_io.h"

namespace qm3d::pointcloud {

void register_metrics(Registry& registry) {
  registry.readers().cloud = [](const std::filesystem::path& path, FileFormat format,
                                const ReadOptions& options) {
    if (format != FileFormat::kPly && format != FileFormat::kPcd) {
      throw FormatError(path.string() + ": not a PLY or PCD point cloud");
    }
    return read_cloud_data(path, format == FileFormat::kPcd ? CloudFormat::kPcd : CloudFormat::kPly,
                           options);
  };
  registry.add(pcqm_spec());
  if (registry.has_sampler()) registry.add(pcqm_sampled_spec(registry.sampler()));
  registry.add(psnr_spec(registry.grid_sampler()));
  registry.add(dlab_spec(registry.colour_matcher()));
  registry.add(graphsim_spec());
  registry.add(msgraphsim_spec());
  registry.add(pointssim_spec());
}

}  // namespace qm3d::pointcloud
