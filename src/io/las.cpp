// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the las implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_las(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": las reader missing"); }
void write_las(const std::filesystem::path& path, const PointCloud&, const WriteOptions&) { throw Error(path.string() + ": las writer missing"); }
}  // namespace pointsurf::io::detail
