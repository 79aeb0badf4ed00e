// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/transform_file.h"

#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

using io::detail::display_name;

void write_transform_file(const std::filesystem::path& path, const TransformFile& file) {
  // One matrix row per line, as people read a 4x4; every number in the shortest form that reads
  // back exactly (nlohmann's).
  const Eigen::Matrix4d m = file.transform.matrix();
  std::string text = "{\n  \"matrix\": [\n";
  for (int r = 0; r < 4; ++r) {
    nlohmann::json row = {m(r, 0), m(r, 1), m(r, 2), m(r, 3)};
    text += "    " + row.dump() + (r < 3 ? ",\n" : "\n");
  }
  text += "  ]";
  for (const auto& [name, value] : file.members) {
    if (name == "matrix") throw UsageError(fmt::format("write_transform_file: {}: a member may not be named \"matrix\"", display_name(path)));
    nlohmann::json v;
    std::visit([&v](const auto& x) { v = x; }, value);
    text += ",\n  " + nlohmann::json(name).dump() + ": " + v.dump();
  }
  text += "\n}\n";
  io::detail::TemporaryOutput out(path);
  {
    io::detail::FileWriter writer(out.path());
    writer.write(text);
    writer.close();
  }
  out.commit();
}

namespace {

Eigen::Matrix4d read_matrix(const nlohmann::json& m, const std::string& file) {
  auto fail = [&](const std::string& what) {
    return InputError(fmt::format("{}: \"matrix\": {} (expected 4 rows of 4 numbers, or 16 numbers row by row)", file, what));
  };
  std::vector<double> numbers;
  if (!m.is_array()) throw fail("not a list");
  if (m.size() == 4 && m[0].is_array()) {
    for (std::size_t r = 0; r < 4; ++r) {
      if (!m[r].is_array() || m[r].size() != 4) throw fail(fmt::format("row {} does not hold 4 numbers", r + 1));
      for (const auto& v : m[r]) {
        if (!v.is_number()) throw fail(fmt::format("row {} holds {}", r + 1, v.dump()));
        numbers.push_back(v.get<double>());
      }
    }
  } else if (m.size() == 16) {
    for (const auto& v : m) {
      if (!v.is_number()) throw fail(fmt::format("{} is not a number", v.dump()));
      numbers.push_back(v.get<double>());
    }
  } else {
    throw fail(fmt::format("a list of {} items", m.size()));
  }
  Eigen::Matrix4d out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(r, c) = numbers[std::size_t(4 * r + c)];
  if (!out.allFinite()) throw fail("a value is not finite");
  return out;
}

}  // namespace

TransformFile read_transform_file(const std::filesystem::path& path) {
  const std::string file = display_name(path);
  const std::string text = io::detail::read_file_bytes(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(fmt::format("{}: not JSON (byte {}): expected a T.json object with a \"matrix\"", file, e.byte));
  }
  if (!j.is_object()) throw InputError(fmt::format("{}: expected a JSON object with a \"matrix\", got {}", file, j.type_name()));
  if (!j.contains("matrix")) throw InputError(fmt::format("{}: no \"matrix\" member (the 4x4 transform, row by row)", file));
  Eigen::Matrix4d m = read_matrix(j["matrix"], file);
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0)
    throw InputError(fmt::format("{}: \"matrix\": the last row must be 0, 0, 0, 1", file));
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const double error = (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > 1e-4 || r.determinant() < 0.0)
    throw InputError(fmt::format("{}: \"matrix\": the 3x3 block is not a rotation (orthonormality error {:.3g}, determinant {:.6g}): the "
                                 "transform must be rigid",
                                 file, error, r.determinant()));
  TransformFile out;
  // A matrix written with 17 digits reads back bit for bit; one with fewer is made a rotation.
  out.transform = RigidTransform(error > 1e-12 ? RigidTransform::nearest_rotation(r) : r, m.topRightCorner<3, 1>());
  for (const auto& [name, v] : j.items()) {
    if (name == "matrix") continue;
    if (v.is_boolean()) out.members.emplace_back(name, v.get<bool>());
    else if (v.is_number_integer()) out.members.emplace_back(name, v.get<std::int64_t>());
    else if (v.is_number()) out.members.emplace_back(name, v.get<double>());
    else if (v.is_string()) out.members.emplace_back(name, v.get<std::string>());
    else if (v.is_array() && std::all_of(v.begin(), v.end(), [](const auto& e) { return e.is_number(); }))
      out.members.emplace_back(name, v.get<std::vector<double>>());
  }
  return out;
}

}  // namespace pointsurf
