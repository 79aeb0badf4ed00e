// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/features.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "register/detail/features_pair.h"

namespace pointsurf {
namespace {

constexpr int kFpfhBins = 11;  // per feature: 3 x 11 = 33
constexpr std::size_t kFpfhDimension = 3 * kFpfhBins;
constexpr int kPfhSplits = 5;  // per feature: 5^3 = 125
constexpr std::size_t kPfhDimension = kPfhSplits * kPfhSplits * kPfhSplits;
constexpr std::size_t kMinPairs = 3;  // a histogram of fewer pairs says little: the point is invalid
constexpr std::size_t kBlock = 256;   // points per parallel task (and per progress report)

bool usable_normal(const Eigen::Vector3d& n) { return n.allFinite() && n.squaredNorm() > 0.0; }

// Per-thread scratch: the neighbour list and, for PFH, the neighbourhood in float offsets.
struct Scratch {
  std::vector<Neighbor> neighbors;
  std::vector<Eigen::Vector3f> offsets, normals;
};

class DescriptorPass {
public:
  DescriptorPass(const PointCloud& cloud, const KdTree& tree, std::size_t max_neighbors, double radius,
                 detail::ProgressReporter& reporter)
      : cloud_(cloud), tree_(tree), max_neighbors_(max_neighbors), radius_(radius), reporter_(reporter) {}

  // Calls visit(i, neighbours, scratch) for every point, in the tree's spatial order, in parallel.
  template <class Visit>
  void run(Visit&& visit) {
    const std::span<const std::uint32_t> order = tree_.spatial_order();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), kBlock), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter_.cancelled()) return;
      Scratch& scratch = scratch_.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        if (!usable_normal(cloud_.normals[i])) continue;
        tree_.hybrid(cloud_.positions[i], max_neighbors_, radius_, scratch.neighbors);
        visit(i, scratch);
      }
      reporter_.advance(r.size());
    });
    reporter_.throw_if_cancelled();
  }

private:
  const PointCloud& cloud_;
  const KdTree& tree_;
  std::size_t max_neighbors_;
  double radius_;
  detail::ProgressReporter& reporter_;
  tbb::enumerable_thread_specific<Scratch> scratch_;
};

// SPFH of point i (Rusu 2009): the three features of the pairs (i, j) over its neighbours j,
// in 11 bins each, each sub-histogram summing to 100. Returns false below kMinPairs pairs.
bool spfh(const PointCloud& cloud, std::uint32_t i, std::span<const Neighbor> neighbors, float* row) {
  std::array<std::uint32_t, kFpfhDimension> counts{};
  const Eigen::Vector3d& p = cloud.positions[i];
  const Eigen::Vector3f n = cloud.normals[i].cast<float>();
  std::size_t pairs = 0;
  for (const Neighbor& nb : neighbors) {
    if (nb.index == i || !usable_normal(cloud.normals[nb.index])) continue;
    detail::PairFeatures f;
    if (!detail::pair_features((cloud.positions[nb.index] - p).cast<float>(), n, cloud.normals[nb.index].cast<float>(), f))
      continue;
    int bins[3];
    detail::feature_bins(f, kFpfhBins, bins);
    ++counts[bins[0]];
    ++counts[kFpfhBins + bins[1]];
    ++counts[2 * kFpfhBins + bins[2]];
    ++pairs;
  }
  if (pairs < kMinPairs) return false;
  const float scale = 100.0f / static_cast<float>(pairs);
  for (std::size_t b = 0; b < kFpfhDimension; ++b) row[b] = scale * static_cast<float>(counts[b]);
  return true;
}

// PFH of point i (Rusu 2008): the features of every pair in the neighbourhood (the point
// included), 5 bins per feature in one 125-bin histogram summing to 100.
bool pfh(const PointCloud& cloud, std::uint32_t i, Scratch& scratch, float* row) {
  const Eigen::Vector3d& p = cloud.positions[i];
  scratch.offsets.clear();
  scratch.normals.clear();
  bool self_found = false;
  for (const Neighbor& nb : scratch.neighbors) {
    if (!usable_normal(cloud.normals[nb.index])) continue;
    self_found = self_found || nb.index == i;
    scratch.offsets.push_back((cloud.positions[nb.index] - p).cast<float>());
    scratch.normals.push_back(cloud.normals[nb.index].cast<float>());
  }
  if (!self_found) {  // the k nearest may all be duplicates of i that precede it
    scratch.offsets.emplace_back(Eigen::Vector3f::Zero());
    scratch.normals.push_back(cloud.normals[i].cast<float>());
  }
  std::array<std::uint32_t, kPfhDimension> counts{};
  std::size_t pairs = 0;
  const std::size_t m = scratch.offsets.size();
  for (std::size_t a = 1; a < m; ++a) {
    for (std::size_t b = 0; b < a; ++b) {
      detail::PairFeatures f;
      if (!detail::pair_features(scratch.offsets[b] - scratch.offsets[a], scratch.normals[a], scratch.normals[b], f)) continue;
      int bins[3];
      detail::feature_bins(f, kPfhSplits, bins);
      ++counts[bins[0] + kPfhSplits * (bins[1] + kPfhSplits * bins[2])];
      ++pairs;
    }
  }
  // At least 3 neighbours besides the point, as for FPFH.
  if (m < kMinPairs + 1 || pairs < kMinPairs) return false;
  const float scale = 100.0f / static_cast<float>(pairs);
  for (std::size_t b = 0; b < kPfhDimension; ++b) row[b] = scale * static_cast<float>(counts[b]);
  return true;
}

// FPFH of point i from the SPFH rows: its own plus the neighbours' weighted by 1 / squared
// distance (as PCL and Open3D weight them), each weighted sub-histogram scaled to sum to 100.
void fpfh(std::uint32_t i, std::span<const Neighbor> neighbors, const std::vector<float>& spfh_rows,
          const std::vector<std::uint8_t>& valid, float* row) {
  std::array<float, kFpfhDimension> sum{};
  for (const Neighbor& nb : neighbors) {
    if (nb.index == i || !valid[nb.index] || !(nb.squared_distance > 0.0)) continue;
    const float weight = static_cast<float>(1.0 / nb.squared_distance);
    const float* other = spfh_rows.data() + std::size_t(nb.index) * kFpfhDimension;
    for (std::size_t b = 0; b < kFpfhDimension; ++b) sum[b] += weight * other[b];
  }
  const float* own = spfh_rows.data() + std::size_t(i) * kFpfhDimension;
  for (int part = 0; part < 3; ++part) {
    float total = 0.0f;
    for (int b = 0; b < kFpfhBins; ++b) total += sum[part * kFpfhBins + b];
    const float scale = total > 0.0f ? 100.0f / total : 0.0f;
    for (int b = 0; b < kFpfhBins; ++b) row[part * kFpfhBins + b] = scale * sum[part * kFpfhBins + b] + own[part * kFpfhBins + b];
  }
}

}  // namespace

const EnumNames<DescriptorType>& descriptor_type_names() {
  static const EnumNames<DescriptorType> names{{{DescriptorType::Fpfh, "fpfh"}, {DescriptorType::Pfh, "pfh"}}};
  return names;
}

const char* descriptor_type_name(DescriptorType type) noexcept { return descriptor_type_names().name(type).c_str(); }

const FieldTable<DescriptorParams>& DescriptorParams::fields() {
  static const FieldTable<DescriptorParams> table = [] {
    using P = DescriptorParams;
    FieldTable<P> t;
    t.choice("descriptor", &P::type, descriptor_type_names(), "Local descriptor matched for the global alignment (PFH: 125 bins, slower)");
    t.length("radius", &P::radius, "Descriptor radius (in spacings: of the downsample, the voxel cell)").positive().was("radius_in_spacings");
    t.integer("max_neighbors", &P::max_neighbors, "Nearest points kept within the radius (the point and 3 neighbours at least)")
        .at_least(double(kMinPairs + 1))
        .unit("points")
        .internal();
    return t;
  }();
  return table;
}

void DescriptorParams::validate() const {
  if (type != DescriptorType::Pfh && type != DescriptorType::Fpfh)
    throw UsageError(fmt::format("compute_descriptors: unknown descriptor type {}", static_cast<int>(type)));
  if (!std::isfinite(radius.value)) throw UsageError(fmt::format("compute_descriptors: radius must be finite, got {}", radius.value));
  fields().validate(*this, "compute_descriptors");
}

Descriptors compute_descriptors(const PointCloud& cloud, const KdTree& tree, const DescriptorParams& params,
                                const ProgressCallback& progress) {
  params.validate();
  const std::size_t n = cloud.size();
  if (!cloud.has_normals()) throw UsageError("compute_descriptors: the cloud has no normals (estimate them first)");
  if (cloud.normals.size() != n)
    throw UsageError(fmt::format("compute_descriptors: the cloud has {} normals for {} points", cloud.normals.size(), n));
  if (tree.size() != n)
    throw UsageError(fmt::format("compute_descriptors: the kd-tree holds {} points but the cloud has {}", tree.size(), n));

  Descriptors out;
  out.type = params.type;
  out.dimension = params.type == DescriptorType::Pfh ? kPfhDimension : kFpfhDimension;
  out.valid.assign(n, 0);
  out.values.assign(n * out.dimension, 0.0f);
  // Fewer points than a neighbourhood needs: every descriptor is invalid (and the mean
  // spacing of a single point is undefined).
  if (n < kMinPairs + 1) {
    out.radius = params.radius.in_spacings() ? 0.0 : params.radius.value;
    return out;
  }
  out.radius = params.radius.in_spacings() ? params.radius.resolve(mean_spacing(tree)) : params.radius.value;

  const bool is_pfh = params.type == DescriptorType::Pfh;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, is_pfh ? n : 2 * n);
  DescriptorPass pass(cloud, tree, params.max_neighbors, out.radius, reporter);
  if (is_pfh) {
    pass.run([&](std::uint32_t i, Scratch& scratch) {
      out.valid[i] = pfh(cloud, i, scratch, out.values.data() + std::size_t(i) * kPfhDimension) ? 1 : 0;
    });
  } else {
    // Two passes over the same neighbourhoods: SPFH of every point, then the weighted sums.
    // Querying twice costs less memory than keeping ~100 neighbours per point between them.
    std::vector<float> spfh_rows(n * kFpfhDimension, 0.0f);
    pass.run([&](std::uint32_t i, Scratch& scratch) {
      out.valid[i] = spfh(cloud, i, scratch.neighbors, spfh_rows.data() + std::size_t(i) * kFpfhDimension) ? 1 : 0;
    });
    pass.run([&](std::uint32_t i, Scratch& scratch) {
      if (out.valid[i]) fpfh(i, scratch.neighbors, spfh_rows, out.valid, out.values.data() + std::size_t(i) * kFpfhDimension);
    });
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return out;
}

}  // namespace pointsurf
