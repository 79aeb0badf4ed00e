// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/context.h"

#include <cstring>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

std::uint64_t positions_checksum(const std::vector<Vector3d>& positions) noexcept {
  // FNV-1a over 64-bit words: a few milliseconds per million points, far below a tree build.
  std::uint64_t h = 1469598103934665603ull ^ positions.size();
  for (const Vector3d& p : positions)
    for (int c = 0; c < 3; ++c) {
      std::uint64_t bits;
      std::memcpy(&bits, &p[c], sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
  return h;
}

void Context::set(const std::string& tag, DataItem item) {
  Entry& e = items_[tag];
  e.item = std::move(item);
  e.cache = std::make_shared<Cache>();
}

void Context::set_cloud(const std::string& tag, PointCloud cloud, std::string source) {
  DataItem item;
  item.mesh.vertices = std::move(cloud);
  item.source = std::move(source);
  set(tag, std::move(item));
}

void DataItem::assign_mesh(TriangleMesh m, std::string mesh_source) {
  if (m.vertices.crs.empty()) m.vertices.crs = std::move(mesh.vertices.crs);  // built from this item's cloud: its CRS stays
  mesh = std::move(m);
  is_mesh = true;
  source = std::move(mesh_source);
}

void Context::set_mesh(const std::string& tag, TriangleMesh mesh, std::string source) {
  DataItem item;
  item.assign_mesh(std::move(mesh), std::move(source));
  set(tag, std::move(item));
}

Context::Entry& Context::entry(const std::string& tag) {
  const auto it = items_.find(tag);
  if (it == items_.end()) {
    std::string known;
    for (const auto& [name, e] : items_) known += (known.empty() ? "" : ", ") + name;
    throw UsageError(fmt::format("no data named \"{}\" (known: {})", tag, known.empty() ? "none" : known));
  }
  return it->second;
}

DataItem& Context::item(const std::string& tag) { return entry(tag).item; }
const DataItem& Context::item(const std::string& tag) const { return const_cast<Context*>(this)->entry(tag).item; }

void Context::rename(const std::string& from, const std::string& to) {
  if (from == to) return;
  Entry moved = std::move(entry(from));
  items_.erase(from);
  items_[to] = std::move(moved);
}

void Context::copy(const std::string& from, const std::string& to) {
  if (from == to) return;
  Entry copied;
  copied.item = entry(from).item;
  // The copy starts with the same positions: it may share the tree; a change to either is
  // noticed by the checksum, and the changed one gets a cache of its own.
  copied.cache = std::make_shared<Cache>(*entry(from).cache);
  items_[to] = std::move(copied);
}

void Context::erase(const std::string& tag) { items_.erase(tag); }

std::vector<std::string> Context::tags() const {
  std::vector<std::string> out;
  for (const auto& [name, e] : items_) out.push_back(name);
  return out;
}

Context::Cache& Context::fresh_cache(Entry& e) {
  const std::vector<Vector3d>& positions = e.item.cloud().positions;
  const std::uint64_t checksum = positions_checksum(positions);
  if (!e.cache) e.cache = std::make_shared<Cache>();
  if (e.cache->tree && (e.cache->size != positions.size() || e.cache->checksum != checksum)) e.cache = std::make_shared<Cache>();
  if (!e.cache->tree) {
    e.cache->tree = std::make_shared<const KdTree>(positions);
    e.cache->checksum = checksum;
    e.cache->size = positions.size();
    e.cache->spacing = -1.0;
    ++tree_builds_;
  }
  return *e.cache;
}

const KdTree& Context::tree(const std::string& tag) { return *fresh_cache(entry(tag)).tree; }

double Context::mean_spacing(const std::string& tag) {
  Cache& cache = fresh_cache(entry(tag));
  if (cache.spacing < 0.0) cache.spacing = cache.tree->size() >= 2 ? pointsurf::mean_spacing(*cache.tree) : 0.0;
  return cache.spacing;
}

}  // namespace pointsurf
