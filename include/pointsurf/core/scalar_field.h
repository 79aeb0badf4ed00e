// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Named per-element scalar fields (intensity, classification, curvature, labels, deviation).
#include <cstdint>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

namespace pointsurf {

/// Storage type a field had in its source file, used when writing it back. Values are held as
/// double in memory whatever the type, which holds every integer up to 2^53 exactly.
enum class ScalarType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

/// Size in bytes of one value of the type.
int scalar_type_size(ScalarType type) noexcept;
/// PLY spelling of the type ("char", "uchar", ..., "double").
std::string_view scalar_type_ply_name(ScalarType type) noexcept;
/// True for Float32 and Float64.
bool scalar_type_is_float(ScalarType type) noexcept;

/// One named field with a value per point (or per mesh vertex).
struct ScalarField {
  std::string name;
  ScalarType type = ScalarType::Float64;  // type to write it back as
  std::vector<double> values;             // one per element
};

/// Fields of a cloud or mesh, in insertion order, names unique.
/// A reference or pointer from add() or find() stays valid while more fields are added (so two
/// fields can be filled side by side); remove() invalidates every one of them.
class FieldSet {
public:
  const ScalarField* find(std::string_view name) const noexcept;
  ScalarField* find(std::string_view name) noexcept;
  bool contains(std::string_view name) const noexcept { return find(name) != nullptr; }
  /// Adds a field of `count` zeros, or returns the existing field of that name resized to count.
  ScalarField& add(std::string name, std::size_t count, ScalarType type = ScalarType::Float64);
  /// Removes the field; returns whether it existed.
  bool remove(std::string_view name);
  std::size_t size() const noexcept { return fields_.size(); }
  bool empty() const noexcept { return fields_.empty(); }
  auto begin() noexcept { return fields_.begin(); }
  auto end() noexcept { return fields_.end(); }
  auto begin() const noexcept { return fields_.begin(); }
  auto end() const noexcept { return fields_.end(); }
  ScalarField& operator[](std::size_t i) { return fields_[i]; }
  const ScalarField& operator[](std::size_t i) const { return fields_[i]; }

private:
  std::deque<ScalarField> fields_;  // a deque: push_back keeps references to earlier fields
};

}  // namespace pointsurf
