// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the xyz implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_xyz(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": xyz reader missing"); }
void write_xyz(const std::filesystem::path& path, const PointCloud&, const WriteOptions&) { throw Error(path.string() + ": xyz writer missing"); }
}  // namespace pointsurf::io::detail
