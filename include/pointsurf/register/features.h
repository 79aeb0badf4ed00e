// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Local shape descriptors for matching two scans: PFH (Rusu, Blodow, Beetz 2008; 125 bins over
// every pair in the neighbourhood) and FPFH (Rusu, Blodow, Beetz 2009; 33 bins, simplified
// histograms of the point and its neighbours weighted by distance). The radius scales with the
// data: by default a multiple of the mean spacing, so a robot scan and the bunny need no tuning.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"

namespace pointsurf {

class KdTree;

enum class DescriptorType : std::uint8_t { Pfh = 0, Fpfh = 1 };
/// "fpfh", "pfh".
const EnumNames<DescriptorType>& descriptor_type_names();
/// "fpfh", "pfh" (descriptor_type_names()).
const char* descriptor_type_name(DescriptorType type) noexcept;

struct DescriptorParams {
  DescriptorType type = DescriptorType::Fpfh;
  Length radius = Length::spacings(10.0);  // neighbourhood radius, cloud units or mean spacings, > 0
  std::size_t max_neighbors = 100;   // nearest points kept within the radius
  /// Key, unit, range and doc of each field (core/fields.h): descriptor, radius.
  static const FieldTable<DescriptorParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// One descriptor per point, row-major: row i is point i's histogram (dimension 125 for PFH,
/// 33 for FPFH). A point with fewer than 3 neighbours or a zero normal gets valid[i] = 0 and a
/// zero row.
struct Descriptors {
  DescriptorType type = DescriptorType::Fpfh;
  std::size_t dimension = 0;
  std::vector<float> values;         // size() x dimension
  std::vector<std::uint8_t> valid;   // size()
  double radius = 0.0;               // the radius used, cloud units
  std::size_t size() const noexcept { return valid.size(); }
  std::span<const float> row(std::size_t i) const noexcept { return {values.data() + i * dimension, dimension}; }
};

/// Descriptors of every point of `cloud` (which must have normals; UsageError otherwise), with
/// `tree` built over its positions. Parallel (oneTBB), points visited in spatial order.
/// The neighbourhood is the point and at most max_neighbors - 1 others within the radius (as
/// Open3D's hybrid search). Pair features as PCL's computePairFeatures; FPFH weights the
/// neighbours' SPFH by 1 / squared distance (as PCL and Open3D), each third of the weighted sum
/// scaled to 100, plus the point's own SPFH (so an FPFH row sums to 600, a PFH row to 100).
/// Cost: FPFH O(N k), PFH O(N k^2) pair features (k = neighbours). Thread-safe.
Descriptors compute_descriptors(const PointCloud& cloud, const KdTree& tree, const DescriptorParams& params,
                                const ProgressCallback& progress = {});

}  // namespace pointsurf
