#include "inverse/optimizer.h"

#include "inverse/ceres_driver.h"
#include "inverse/nlopt_driver.h"

namespace chordfit::inverse {

const std::vector<std::string>& optimizerNames() {
  static const std::vector<std::string> names = {"ceres", "bobyqa", "cobyla", "sbplx", "crs2"};
  return names;
}

std::unique_ptr<Optimizer> makeOptimizer(const std::string& name) {
  if (name == "ceres") return std::make_unique<CeresDriver>();
  if (name == "bobyqa" || name == "cobyla" || name == "sbplx" || name == "crs2") {
    return std::make_unique<NloptDriver>(name);
  }
  return nullptr;
}

}  // namespace chordfit::inverse
