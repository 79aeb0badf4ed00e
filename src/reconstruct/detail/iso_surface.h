// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Iso-surface extraction on an octree lattice, shared by the implicit reconstructions (Poisson
// now, MLS / RBF / MPU later). The extractor knows nothing of how the function was built: it
// asks an IsoFunction for values at lattice corners and for gradients at points, and asks
// where the octree is refined, so that it meshes each region at its leaves' resolution.
//
// This header is the contract between the solver (reconstruct/poisson.cpp) and the extractor
// (reconstruct/iso_surface.cpp); extend it, don't change the meaning of what is here.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/progress.h"

namespace pointsurf::detail {

/// The cube [origin, origin + size]^3 divided into (2^depth)^3 finest cells. A corner at level
/// l (0 <= l <= depth) is an integer triple c in [0, 2^l]^3 at origin + size * c / 2^l; a cell
/// at level l is the triple of its lowest corner.
struct IsoLattice {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double size = 1.0;
  int depth = 0;

  Eigen::Vector3d corner_position(int level, const std::array<std::uint32_t, 3>& c) const {
    const double h = size / static_cast<double>(std::uint64_t{1} << level);
    return origin + h * Eigen::Vector3d(c[0], c[1], c[2]);
  }
};

/// The implicit function to contour. Every member is called concurrently from worker threads.
class IsoFunction {
 public:
  virtual ~IsoFunction() = default;

  /// Values at `n` corners of `level` (corners[3 * i + 0..2]). A corner's value must not depend
  /// on the batch it comes in: the extractor may ask for a corner twice (once per brick of cells
  /// that needs it) and the two answers must classify it the same way.
  virtual void corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const = 0;

  /// Value at an arbitrary point (root refinement along an edge).
  virtual double value(const Eigen::Vector3d& p) const = 0;

  /// Gradient at an arbitrary point (vertex normals: -gradient / |gradient| when the inside is
  /// positive, which the caller states in IsoSurfaceParams::inside_positive).
  virtual Eigen::Vector3d gradient(const Eigen::Vector3d& p) const = 0;

  /// Whether the octree cell `cell` at `level` (< lattice depth) has children: the extractor
  /// descends only where it does, and meshes a leaf at the leaf's own level.
  virtual bool refined(int level, const std::array<std::uint32_t, 3>& cell) const = 0;
};

struct IsoSurfaceParams {
  double iso_value = 0.0;
  bool inside_positive = true;   // the function is larger than iso_value inside the surface
  int root_refinement_steps = 1; // per edge crossing: 0 linear in the corner values; 1 the quadratic
                                 // through the edge midpoint (exact for degree-2 B-splines with knots
                                 // on lattice corners); more: further false-position steps on value()
                                 // (3: Poisson elephant 100k depth 8 Chamfer -11 %)
  // for progress only, the caller's estimates (0: none): the finest cells the surface following
  // will process (then followed by count, else round by round) and the coarse seeds' share of
  // the extraction's time (else half)
  double expected_cells = 0.0, seed_share = 0.0;
};

/// The extracted surface: closed (watertight) wherever it does not leave the lattice, edge- and
/// vertex-manifold, crack-free across leaves of different levels, triangles counter-clockwise
/// seen from outside.
struct IsoSurface {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3d> normals;              // unit, from the function's gradient
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

/// Contours `f` at params.iso_value over the leaves of the octree that `f.refined` describes.
/// The implementation (reconstruct/iso_surface.cpp) meshes at the octree's finest level (the
/// deepest level that has leaves, at most lattice.depth) wherever the surface goes, coarse leaves
/// included, which makes it crack-free by construction: every finest
/// leaf, and every finest cell where a coarse leaf's edge changes sign, seeds a search that follows
/// the surface cell by cell. A surface part that crosses no edge of any leaf (a bubble smaller than
/// the coarse leaf around it) is not found. Output order is deterministic: the same mesh for any
/// thread count.
/// Throws CancelledError when `progress` returns false.
IsoSurface extract_iso_surface(const IsoFunction& f, const IsoLattice& lattice, const IsoSurfaceParams& params,
                               const ProgressCallback& progress = {});

}  // namespace pointsurf::detail
