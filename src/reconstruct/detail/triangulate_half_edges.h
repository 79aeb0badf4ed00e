// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Directed edges (half-edges) of a growing triangle mesh in one open-addressing hash table:
// (from, to) -> triangle. One flat array instead of per-vertex lists, so that a million-point
// selection makes no per-vertex heap allocation; key and triangle share a slot, so that a
// look-up that finds its edge touches one cache line, not two.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pointsurf::detail {

class HalfEdgeMap {
public:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  explicit HalfEdgeMap(std::size_t expected = 1024) { rehash(capacity_for(expected)); }
  /// With `vertex_rank` (one entry per vertex, a permutation of 0..n-1 in spatial order, e.g. a
  /// kd-tree's leaf order; it must outlive the map), an edge's slot follows the rank of its first
  /// vertex: the edges of nearby vertices share cache lines, so walking a fan or growing a front
  /// touches a few lines instead of one per look-up. Look-ups give the same answers either way.
  HalfEdgeMap(std::size_t expected, const std::vector<std::uint32_t>* vertex_rank) : rank_(vertex_rank) {
    rehash(capacity_for(expected));
  }

  /// The triangle holding the directed edge from -> to, or kNone.
  std::uint32_t find(std::uint32_t from, std::uint32_t to) const noexcept {
    const std::uint64_t key = make_key(from, to);
    for (std::size_t slot = hash(key) & mask_;; slot = (slot + 1) & mask_) {
      if (slots_[slot].key == key) return slots_[slot].value;
      if (slots_[slot].key == kEmpty) return kNone;
    }
  }
  bool contains(std::uint32_t from, std::uint32_t to) const noexcept { return find(from, to) != kNone; }

  /// Records from -> to as an edge of `triangle` (the caller checked it is not there yet).
  void insert(std::uint32_t from, std::uint32_t to, std::uint32_t triangle) {
    if (2 * (count_ + 1) > slots_.size()) grow();
    place(make_key(from, to), triangle);
    ++count_;
  }

  /// Removes the entry from -> to of `triangle` if present (a duplicated edge keeps its other
  /// entries). Backward-shift deletion: no tombstones, lookups stay short.
  void erase(std::uint32_t from, std::uint32_t to, std::uint32_t triangle) noexcept {
    const std::uint64_t key = make_key(from, to);
    std::size_t hole = hash(key) & mask_;
    for (;; hole = (hole + 1) & mask_) {
      if (slots_[hole].key == key && slots_[hole].value == triangle) break;
      if (slots_[hole].key == kEmpty) return;
    }
    for (std::size_t j = (hole + 1) & mask_; slots_[j].key != kEmpty; j = (j + 1) & mask_) {
      // The entry at j may fill the hole unless its home slot lies cyclically in (hole, j].
      const std::size_t home = hash(slots_[j].key) & mask_;
      if (((j - home) & mask_) >= ((j - hole) & mask_)) {
        slots_[hole] = slots_[j];
        hole = j;
      }
    }
    slots_[hole] = Slot{};
    --count_;
  }

  /// Replaces each stored triangle t by new_id[t] (after the triangles were renumbered): one
  /// sequential pass over the table instead of inserting every edge again.
  void renumber(const std::vector<std::uint32_t>& new_id) noexcept {
    for (Slot& slot : slots_)
      if (slot.key != kEmpty) slot.value = new_id[slot.value];
  }

private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  struct Slot {
    std::uint64_t key = kEmpty;
    std::uint32_t value = kNone;
  };
  static std::uint64_t make_key(std::uint32_t from, std::uint32_t to) noexcept {
    return (std::uint64_t{from} << 32) | std::uint64_t{to};
  }
  std::size_t hash(std::uint64_t key) const noexcept {
    if (rank_ != nullptr) {
      // Slots in rank order, about capacity / n per vertex, spread a little by the second vertex.
      const std::uint64_t r = (*rank_)[key >> 32];
      const std::uint64_t to = key & 0xffffffffu;
      return static_cast<std::size_t>(((r * spread_) >> 16) + (((to * 0x9e3779b1u) & 0xffffffffu) >> 30));
    }
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return static_cast<std::size_t>(key);
  }
  static std::size_t capacity_for(std::size_t expected) {
    std::size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    return capacity;
  }
  void place(std::uint64_t key, std::uint32_t value) noexcept {
    std::size_t slot = hash(key) & mask_;
    while (slots_[slot].key != kEmpty) slot = (slot + 1) & mask_;
    slots_[slot] = Slot{key, value};
  }
  void rehash(std::size_t capacity) {
    std::vector<Slot> old(capacity);
    old.swap(slots_);
    mask_ = capacity - 1;
    if (rank_ != nullptr && !rank_->empty()) spread_ = (std::uint64_t(capacity) << 16) / rank_->size();
    for (const Slot& slot : old)
      if (slot.key != kEmpty) place(slot.key, slot.value);
  }
  void grow() { rehash(slots_.size() * 2); }

  std::vector<Slot> slots_;
  std::size_t mask_ = 0;
  std::size_t count_ = 0;
  const std::vector<std::uint32_t>* rank_ = nullptr;
  std::uint64_t spread_ = 0;  // slots per vertex rank, 16-bit fixed point
};

}  // namespace pointsurf::detail
