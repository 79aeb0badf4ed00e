// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Registration of two scans from nothing but their points: normals where missing, a voxel
// downsample, descriptors (PFH or FPFH), global alignment by RANSAC over descriptor matches,
// then ICP, first on the downsample and then on every point. Every length defaults to a
// multiple of the mean spacing, so the same defaults serve a statue and a building. What the
// `register` stage, the command line and Python call.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/register/align.h"
#include "pointsurf/register/features.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/register/result.h"

namespace pointsurf {

struct RegisterPairParams {
  Length voxel = Length::spacings(2.0);  // the global alignment and the coarse ICP work on a voxel
                                     // downsample of this cell, cloud units or mean spacings
                                     // (the larger of the two clouds'); 0 keeps every point
  int normal_neighbors = 30;         // k of the PCA normals estimated for a cloud without any
                                     // (oriented by MST), >= 3
  DescriptorParams features;         // descriptors of the downsample; a radius in spacings counts
                                     // the downsample's spacing (the voxel cell)
  AlignParams align;                 // RANSAC on the downsample; a distance in spacings likewise
  IcpParams icp;                     // the fine ICP on every point; a distance in spacings counts
                                     // the larger mean spacing of the two clouds
  bool global = true;                // false: skip descriptors and RANSAC, start ICP at `initial`
  RigidTransform initial;            // the start when global is false (source onto target)
  double min_fitness = 0.1;          // a final fitness below this means the clouds were not
                                     // found to overlap: converged = false, said in `message`
  /// Key, unit, range and doc of each field (core/fields.h), those of features, align and icp
  /// included.
  static const FieldTable<RegisterPairParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// The answer and what each step took.
struct RegisterPairResult {
  RegistrationResult result;          // the final answer (after the fine ICP): source onto target
  RegistrationResult global;          // RANSAC's answer (global = true)
  RegistrationResult coarse;          // the coarse ICP's answer on the downsample
  double spacing = 0.0;               // the larger mean spacing of the two clouds, cloud units
  double voxel = 0.0;                 // the downsample's cell, cloud units (0: none)
  std::size_t source_samples = 0;     // points of the downsamples
  std::size_t target_samples = 0;
  bool source_normals_estimated = false;  // the cloud had no normals: estimated (PCA, k =
  bool target_normals_estimated = false;  // normal_neighbors, MST-oriented)
  double seconds_prepare = 0.0;       // normals, spacing, downsample, kd-trees
  double seconds_descriptors = 0.0;
  double seconds_align = 0.0;         // matching and RANSAC
  double seconds_icp = 0.0;           // coarse and fine ICP

  /// The reported members (core/results.h): the downsamples, the transform, the final fit
  /// (RegistrationResult's), with `global` RANSAC's fit under "global_", then the lengths and
  /// times.
  static const ResultTable<RegisterPairResult>& results(bool global = false);
};

/// The rigid transform taking `source` onto `target`. Clouds without normals get PCA normals
/// (the result says so). Throws InputError when either cloud has fewer than
/// kMinRegistrationPoints points or coincides with a single point, UsageError for bad
/// parameters, CancelledError when `progress` returns false. A registration that fails (no
/// overlap, no consistent match) is an answer: converged = false with the reason in `message`.
/// Every step is bounded (RANSAC by max_iterations, ICP by its iterations). Works in frames
/// centred on the target, so 1e6 m coordinates lose nothing. Thread-safe.
RegisterPairResult register_pair(const PointCloud& source, const PointCloud& target, const RegisterPairParams& params = {},
                                 const ProgressCallback& progress = {});

/// Fewest points a cloud must have to be registered.
inline constexpr std::size_t kMinRegistrationPoints = 10;

}  // namespace pointsurf
