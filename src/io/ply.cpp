// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the ply implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_ply(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": ply reader missing"); }
void write_ply(const std::filesystem::path& path, const PointCloud&, const std::vector<Triangle>&, const WriteOptions&) { throw Error(path.string() + ": ply writer missing"); }
}  // namespace pointsurf::io::detail
