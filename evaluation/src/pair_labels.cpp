#include "qm3d/evaluation/pair_labels.h"

#include <cmath>

namespace qm3d::evaluation {

double observers_from_ci(double sd, double ci95) {
  return ci95 > 0 ? std::pow(kZ95 * sd / ci95, 2) : 0.0;
}

std::optional<PairLabels> label_pairs(const std::vector<double>& mos, const PairLabelSource& source,
                                      const std::vector<std::string>& groups) {
  switch (source.kind) {
    case PairLabelSource::Kind::sd:
      return label_pairs_j149(mos, source.sd, source.n, groups);
    case PairLabelSource::Kind::raw:
      return label_pairs_raw(source.raw, groups);
    case PairLabelSource::Kind::given:
      return source.given;
    case PairLabelSource::Kind::none:
      break;
  }
  return std::nullopt;
}

}  // namespace qm3d::evaluation
