// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// T.json: a rigid transform with how it was found, as `pointsurf register` writes it and the
// `transform` stage reads it:
//   {"matrix": [[r11, r12, r13, t1], [r21, r22, r23, t2], [r31, r32, r33, t3], [0, 0, 0, 1]],
//    "fitness": 0.93, "inlier_rmse": 0.0012, "iterations": 14, "converged": true, ...}
// `matrix` is 4x4, row-major, mapping the source's points onto the target (p' = R p + t).
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/rigid_transform.h"

namespace pointsurf {

/// A scalar member of a T.json file besides the matrix, or a list of numbers.
using TransformFileValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>>;

struct TransformFile {
  RigidTransform transform;  // "matrix": maps the source onto the target
  std::vector<std::pair<std::string, TransformFileValue>> members;  // the other members, in file
                             // order (writing) or name order (reading); objects and nested
                             // lists are skipped on reading
};

/// Writes `file` as JSON to `path` through a temporary file renamed at the end (the output is
/// whole or absent). The matrix is written with 17 significant digits, so it reads back
/// exactly. Throws Error when the file cannot be written, UsageError for a member named
/// "matrix".
void write_transform_file(const std::filesystem::path& path, const TransformFile& file);

/// Reads a T.json file. `matrix` may be 4 rows of 4 numbers or 16 numbers row by row; its
/// rotation block is projected onto the nearest rotation when it is orthonormal within 1e-4
/// (hand-written files carry few digits) and refused beyond. Throws InputError naming the file
/// and what is wrong (not JSON, no "matrix", a wrong shape, not rigid).
TransformFile read_transform_file(const std::filesystem::path& path);

}  // namespace pointsurf
