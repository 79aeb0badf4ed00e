// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <functional>

namespace pointsurf {

/// Progress of a long stage: called with the finished fraction in [0, 1]; return false to
/// cancel (the stage then throws CancelledError). May be called from any worker thread, but
/// never from two threads at once. An empty function means no reporting.
using ProgressCallback = std::function<bool(double fraction)>;

}  // namespace pointsurf
