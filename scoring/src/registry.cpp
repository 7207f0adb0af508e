#include "qm3d/scoring/registry.h"

#include "qm3d/mesh/metrics.h"
#include "qm3d/pointcloud/metrics.h"
#include "qm3d/render/ibsm.h"

namespace qm3d::scoring {

const Registry& default_registry() {
  static const Registry r = [] {
    Registry reg;
    mesh::register_metrics(reg);
    pointcloud::register_metrics(reg);
    render::register_metrics(reg);
    return reg;
  }();
  return r;
}

}  // namespace qm3d::scoring
