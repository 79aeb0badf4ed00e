// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The data a pipeline works on: named clouds and meshes, with each cloud's kd-tree and mean
// spacing cached until its positions change, so that a chain of stages builds each tree once.
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"
#include "pointsurf/segment/outlines.h"

namespace pointsurf {

/// One named item: a cloud (the vertices of `mesh`, without triangles) or a mesh.
/// What `evaluate` measured on an item: the field holding the deviation and the tolerance it
/// was judged by; `render` takes both by default.
struct MeasuredField {
  std::string field;
  double tolerance = 0.0;  // cloud units
};

struct DataItem {
  TriangleMesh mesh;  // a mesh's face fields are cleared with its triangles
  bool is_mesh = false;
  std::string source;  // tag of the cloud a mesh was built from, or the file it was read from
  std::vector<ScanPose> scans;  // E57 scans read with keep_poses: the pose of each value of field "scan"
  std::optional<MeasuredField> measured;  // set by evaluate
  std::vector<SegmentPlane> segment_planes;  // set by segment (ransac): the planes of field "segment"
  std::vector<Vector3d> scanners;  // E57 read with its poses applied: each scan's sensor position
                                   // (its value of field "scan"); normals face them by default

  /// The points: a cloud's, or a mesh's vertices with their attributes.
  PointCloud& cloud() noexcept { return mesh.vertices; }
  const PointCloud& cloud() const noexcept { return mesh.vertices; }
  /// Becomes `m`, a mesh built from `mesh_source`.
  void assign_mesh(TriangleMesh m, std::string mesh_source);
};

class Context {
public:
  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// Stores `item` under `tag`, replacing any item of that name (and its cache).
  void set(const std::string& tag, DataItem item);
  void set_cloud(const std::string& tag, PointCloud cloud, std::string source = {});
  void set_mesh(const std::string& tag, TriangleMesh mesh, std::string source);
  bool has(const std::string& tag) const { return items_.count(tag) > 0; }
  /// The item under `tag`; throws UsageError naming the known tags when absent. A stage may
  /// change attributes, fields and faces through it; after moving or replacing positions it
  /// need not tell: the cache notices (a checksum of the positions) and rebuilds.
  DataItem& item(const std::string& tag);
  const DataItem& item(const std::string& tag) const;
  /// Renames an item, keeping its cache (a chain passes its cloud on without a copy).
  void rename(const std::string& from, const std::string& to);
  /// Copies an item; the copy shares the cached tree until either changes.
  void copy(const std::string& from, const std::string& to);
  void erase(const std::string& tag);
  std::vector<std::string> tags() const;

  /// The kd-tree over the item's positions, built on first use and after they change.
  const KdTree& tree(const std::string& tag);
  /// The mean spacing of the item's positions (see pointsurf::mean_spacing), cached likewise.
  double mean_spacing(const std::string& tag);
  /// kd-trees built so far, in all and for the positions of `tag`'s current item.
  std::size_t tree_builds() const noexcept { return tree_builds_; }

private:
  struct Cache {
    std::shared_ptr<const KdTree> tree;
    std::uint64_t checksum = 0;
    std::size_t size = 0;
    double spacing = -1.0;
  };
  struct Entry {
    DataItem item;
    std::shared_ptr<Cache> cache;
  };
  Entry& entry(const std::string& tag);
  Cache& fresh_cache(Entry& e);
  std::map<std::string, Entry> items_;
  std::size_t tree_builds_ = 0;
};

/// Checksum of positions (their bytes), how the cache notices a change. O(N).
std::uint64_t positions_checksum(const std::vector<Vector3d>& positions) noexcept;

}  // namespace pointsurf
