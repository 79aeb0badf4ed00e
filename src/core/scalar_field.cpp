// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/scalar_field.h"

#include <algorithm>

namespace pointsurf {

int scalar_type_size(ScalarType type) noexcept {
  switch (type) {
    case ScalarType::Int8: case ScalarType::UInt8: return 1;
    case ScalarType::Int16: case ScalarType::UInt16: return 2;
    case ScalarType::Int32: case ScalarType::UInt32: case ScalarType::Float32: return 4;
    case ScalarType::Int64: case ScalarType::UInt64: case ScalarType::Float64: return 8;
  }
  return 8;
}

std::string_view scalar_type_ply_name(ScalarType type) noexcept {
  switch (type) {
    case ScalarType::Int8: return "char";
    case ScalarType::UInt8: return "uchar";
    case ScalarType::Int16: return "short";
    case ScalarType::UInt16: return "ushort";
    case ScalarType::Int32: return "int";
    case ScalarType::UInt32: return "uint";
    case ScalarType::Int64: return "int64";   // not in the PLY standard; written as double by PLY
    case ScalarType::UInt64: return "uint64";
    case ScalarType::Float32: return "float";
    case ScalarType::Float64: return "double";
  }
  return "double";
}

bool scalar_type_is_float(ScalarType type) noexcept {
  return type == ScalarType::Float32 || type == ScalarType::Float64;
}

const ScalarField* FieldSet::find(std::string_view name) const noexcept {
  auto it = std::find_if(fields_.begin(), fields_.end(), [&](const ScalarField& f) { return f.name == name; });
  return it == fields_.end() ? nullptr : &*it;
}

ScalarField* FieldSet::find(std::string_view name) noexcept {
  auto it = std::find_if(fields_.begin(), fields_.end(), [&](const ScalarField& f) { return f.name == name; });
  return it == fields_.end() ? nullptr : &*it;
}

ScalarField& FieldSet::add(std::string name, std::size_t count, ScalarType type) {
  if (ScalarField* existing = find(name)) {
    existing->values.resize(count, 0.0);
    return *existing;
  }
  fields_.push_back(ScalarField{std::move(name), type, std::vector<double>(count, 0.0)});
  return fields_.back();
}

bool FieldSet::remove(std::string_view name) {
  auto it = std::find_if(fields_.begin(), fields_.end(), [&](const ScalarField& f) { return f.name == name; });
  if (it == fields_.end()) return false;
  fields_.erase(it);
  return true;
}

}  // namespace pointsurf
