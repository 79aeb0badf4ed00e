// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "pointsurf/core/error.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {
namespace {

// SplitMix64: a counter-based generator, so each point's draw depends only on (seed, index)
// and the draws can be made in parallel.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

const FieldTable<CurvatureSimplifyParams>& CurvatureSimplifyParams::fields() {
  static const FieldTable<CurvatureSimplifyParams> table = [] {
    using P = CurvatureSimplifyParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.integer("k", &P::k, "Neighbours for normals and variation when the input has none").at_least(3).unit("points");
    t.number("flat_weight", &P::flat_weight, "Weight of a flat point relative to the mean variation").non_negative();
    t.integer("seed", &P::seed, "Random seed");
    return t;
  }();
  return table;
}

void CurvatureSimplifyParams::validate() const { fields().validate(*this, "simplify_curvature"); }

SimplifyResult simplify_curvature(const PointCloud& cloud, const CurvatureSimplifyParams& params, const KdTree* tree,
                                  const ProgressCallback& progress) {
  detail::check_simplify_input("simplify_curvature", cloud, params.target, false);
  params.validate();
  const std::size_t n = cloud.size();
  const std::size_t m = detail::target_count(params.target, n);
  std::vector<double> variation;
  if (const ScalarField* f = cloud.fields.find("variation"); f != nullptr) {
    variation = f->values;
  } else {
    std::optional<KdTree> own;
    const KdTree& t = detail::tree_or_own("simplify_curvature", cloud, tree, own);
    variation = detail::surface_properties(cloud, params.k, t, false, progress).variation;
  }
  const double mean = tbb::parallel_reduce(
                          tbb::blocked_range<std::size_t>(0, n, 4096), 0.0,
                          [&](const tbb::blocked_range<std::size_t>& r, double s) {
                            for (std::size_t i = r.begin(); i != r.end(); ++i) s += variation[i];
                            return s;
                          },
                          std::plus<>()) /
                      double(n);
  // Weighted sampling without replacement (Efraimidis & Spirakis): keep the m largest
  // u^(1/w), compared as log(u)/w. A zero weight everywhere (all flat, flat_weight 0) falls
  // back to uniform weights.
  const double floor_weight = params.flat_weight * mean;
  std::vector<double> key(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const double u = (double(splitmix64(params.seed ^ (i * 0xd1b54a32d192ed03ull)) >> 11) + 0.5) * 0x1.0p-53;
      double w = std::max(variation[i], 0.0) + floor_weight;
      if (!(w > 0.0)) w = mean > 0.0 || floor_weight > 0.0 ? 1e-300 : 1.0;
      key[i] = std::log(u) / w;
    }
  });
  std::vector<std::size_t> index(n);
  std::iota(index.begin(), index.end(), std::size_t(0));
  const auto larger = [&](std::size_t a, std::size_t b) { return key[a] > key[b] || (key[a] == key[b] && a < b); };
  if (m < n) std::nth_element(index.begin(), index.begin() + std::ptrdiff_t(m), index.end(), larger);
  index.resize(m);
  std::sort(index.begin(), index.end());
  SimplifyResult result;
  result.input_points = n;
  result.cloud = cloud.select(index);
  result.source_index = std::move(index);
  return result;
}

}  // namespace pointsurf
