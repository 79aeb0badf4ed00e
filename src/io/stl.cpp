// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the stl implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_stl(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": stl reader missing"); }
void write_stl(const std::filesystem::path& path, const PointCloud&, const std::vector<Triangle>&, const WriteOptions&) { throw Error(path.string() + ": stl writer missing"); }
}  // namespace pointsurf::io::detail
