// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the obj implementation.
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
RawData read_obj(const std::filesystem::path& path, const ReadOptions&) { throw InputError(path.string() + ": obj reader missing"); }
void write_obj(const std::filesystem::path& path, const PointCloud&, const std::vector<Triangle>&, const WriteOptions&) { throw Error(path.string() + ": obj writer missing"); }
}  // namespace pointsurf::io::detail
