// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <numeric>
#include <random>

#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {

const FieldTable<RandomParams>& RandomParams::fields() {
  static const FieldTable<RandomParams> table = [] {
    using P = RandomParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.integer("seed", &P::seed, "Random seed");
    return t;
  }();
  return table;
}

void RandomParams::validate() const { fields().validate(*this, "simplify_random"); }

SimplifyResult simplify_random(const PointCloud& cloud, const RandomParams& params) {
  detail::check_simplify_input("simplify_random", cloud, params.target, false);
  params.validate();
  const std::size_t n = cloud.size();
  const std::size_t m = detail::target_count(params.target, n);
  std::vector<std::size_t> index(n);
  std::iota(index.begin(), index.end(), std::size_t(0));
  // Partial Fisher-Yates: the first m entries become a uniform random m-subset.
  std::mt19937_64 rng(params.seed);
  for (std::size_t i = 0; i < m && i + 1 < n; ++i) {
    std::uniform_int_distribution<std::size_t> pick(i, n - 1);
    std::swap(index[i], index[pick(rng)]);
  }
  index.resize(m);
  std::sort(index.begin(), index.end());
  SimplifyResult result;
  result.input_points = n;
  result.cloud = cloud.select(index);
  result.source_index = std::move(index);
  return result;
}

}  // namespace pointsurf
