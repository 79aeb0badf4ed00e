// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The screened Poisson system of reconstruct_poisson (Kazhdan, Bolitho, Hoppe 2006; Kazhdan and
// Hoppe 2013) on an adaptive octree in a degree-2 B-spline basis, solved coarse to fine.
//
// Coordinates are local: the samples are mapped into the unit cube [0, 1]^3 by the caller
// (centre and scale of their bounding box), so that an offset of 1e6 m loses nothing.
//
// The octree: level l has the nodes (B-spline functions, one per cell, centred on it) that are
// the 8 children of its "refined" cells at level l - 1. Levels 1..full_depth are complete; below,
// a cell is refined when it lies within 2 cells (1 above the finest level) of a cell that holds
// a sample. This is the band
// the B-spline supports of the samples reach, plus what the 5^3 Laplacian stencil and the
// exact prolongation between levels need (see poisson_solver.cpp), and nothing else: no dense
// grid below full_depth.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/progress.h"
#include "reconstruct/detail/iso_surface.h"

namespace pointsurf::detail {

struct PoissonSample {
  Eigen::Vector3d position;  // in the unit cube
  Eigen::Vector3d normal;    // outward; its length is the sample's confidence (1 without)
};

struct PoissonSystemParams {
  int depth = 8;                  // finest level
  int full_depth = 5;             // levels 1..full_depth complete
  int kernel_depth = 6;           // density estimate's level
  double point_weight = 4.0;      // alpha (PoissonRecon's --pointWeight)
  double samples_per_node = 1.5;  // each normal goes to the level where a node holds this many
  bool dirichlet = false;         // boundary: Neumann (default) or Dirichlet (zero)
  int max_iterations = 8;         // conjugate-gradient iterations per sparse level at most
  double tolerance = 1e-3;        // ... stop when the residual fell by this factor
};

struct PoissonLevelReport {
  int level = 0;
  std::size_t nodes = 0;
  int iterations = 0;
  double initial_residual = 0.0;  // |b - A x| before / after this level's solve
  double final_residual = 0.0;
};

// The pieces of one level's solve (PoissonFunction's solve_level, whose phases are the members
// of its LevelSolve in poisson_solver.cpp) that are pure functions of their inputs, tested alone.

/// The area-weighted mean of the samples q[first..last) that reach `level` (level_of >= level),
/// written to `mean`; returns their total area (the screening point's weight).
double merge_samples(const std::vector<Eigen::Vector3d>& q, const std::vector<double>& area,
                     const std::vector<std::uint8_t>& level_of, std::uint32_t first, std::uint32_t last, int level,
                     Eigen::Vector3d& mean);

/// The indices of `cells` in 27 classes by their coordinates mod 3 (class x%3 + 3 (y%3) + 9 (z%3)),
/// each class in index order: two cells of a class are 3 or more apart along some axis, so the
/// 3^3 nodes around them are disjoint and a class scatters into them in parallel without races.
std::array<std::vector<std::uint32_t>, 27> colour_classes(const std::vector<std::array<int, 3>>& cells);

struct PcgResult {
  int iterations = 0;
  double initial_residual = 0.0;  // |r| on entry
  double final_residual = 0.0;    // |r| on return
};

/// Jacobi-preconditioned conjugate gradients for A x = r from x = 0 (x resized by the caller),
/// `apply(v, out)` writing A v to out, `diag` A's diagonal: at most max_iterations steps, stops
/// when |r| fell by `tolerance` or a direction has no positive curvature. On return r holds the
/// residual. Deterministic: the reductions are in a fixed order for any thread count.
/// `on_iteration`, when given, hears each finished iteration's number (for progress).
PcgResult jacobi_pcg(const std::function<void(const std::vector<double>&, std::vector<double>&)>& apply,
                     std::vector<double>& r, const std::vector<double>& diag, std::vector<double>& x, int max_iterations,
                     double tolerance, const std::function<void(int iteration)>& on_iteration = {});

/// The solved implicit function: sum over the levels of their B-splines. Smaller inside (the
/// normals point outward: the function grows along them), evaluated in the unit cube.
class PoissonFunction final : public IsoFunction {
 public:
  /// Builds the octree over `samples` (sorted by the caller, any order works), estimates the
  /// density, splats the normals and solves. Thread-safe; parallel with oneTBB.
  /// `frame`: where the unit cube lies in cloud units (its depth is params.depth); value(),
  /// gradient() and density_depth() take points in cloud units, corner_values() lattice corners.
  /// `on_octree`, when given, hears the nodes per level (index 0: level 1) once the octree is
  /// built, before the splatting: the caller's progress model decides its split there.
  PoissonFunction(std::vector<PoissonSample> samples, const PoissonSystemParams& params, const IsoLattice& frame,
                  const ProgressCallback& progress = {},
                  const std::function<void(const std::vector<std::size_t>& nodes_per_level)>& on_octree = {});
  ~PoissonFunction() override;

  void corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const override;
  double value(const Eigen::Vector3d& p) const override;
  Eigen::Vector3d gradient(const Eigen::Vector3d& p) const override;
  bool refined(int level, const std::array<std::uint32_t, 3>& cell) const override;

  /// The finest level that holds nodes: the samples reach no deeper (at most params.depth).
  int finest_level() const { return finest_level_; }
  /// The weighted mean of the function at the samples.
  double iso_value() const { return iso_value_; }
  /// The density at p in depth units: the (fractional) level at which a node around p holds
  /// samples_per_node samples (PoissonRecon's --density), in [0, depth].
  double density_depth(const Eigen::Vector3d& p) const;
  const std::vector<PoissonLevelReport>& levels() const { return reports_; }
  /// Bytes held by the octree and its per-node and per-sample arrays at their largest.
  std::size_t peak_bytes() const { return peak_bytes_; }
  /// The function's value at each sample (in the order given).
  const std::vector<double>& sample_values() const { return sample_values_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  IsoLattice frame_;
  double iso_value_ = 0.0;
  int finest_level_ = 1;
  std::vector<PoissonLevelReport> reports_;
  std::size_t peak_bytes_ = 0;
  std::vector<double> sample_values_;
};

}  // namespace pointsurf::detail
