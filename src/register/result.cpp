// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/result.h"

namespace pointsurf {

const ResultTable<RegistrationResult>& RegistrationResult::results() {
  static const ResultTable<RegistrationResult> table = [] {
    using R = RegistrationResult;
    ResultTable<R> t;
    t.number("fitness", &R::fitness, "Share of source points within the fit's distance of the target").higher_is_better();
    t.number("inlier_rmse", &R::inlier_rmse, "RMS distance of those points").with_unit("cloud units").lower_is_better();
    t.computed("iterations", ResultType::Integer, [](const R& r) { return ResultValue(std::int64_t(r.iterations)); }, "ICP iterations");
    t.flag("converged", &R::converged, "The fit converged").higher_is_better();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
