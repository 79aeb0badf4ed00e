// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the off implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_off(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": off reader missing"); }
void write_off(const std::filesystem::path& path, const PointCloud&, const std::vector<Triangle>&, const WriteOptions&) { throw Error(path.string() + ": off writer missing"); }
}  // namespace pointsurf::io::detail
