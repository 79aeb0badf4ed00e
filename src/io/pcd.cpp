// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the pcd implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_pcd(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": pcd reader missing"); }
void write_pcd(const std::filesystem::path& path, const PointCloud&, const WriteOptions&) { throw Error(path.string() + ": pcd writer missing"); }
}  // namespace pointsurf::io::detail
