// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The compiled core of the Python module: the data classes over numpy views, and the stage runner
// over the registry. python/pointsurf/__init__.py builds the public functions on top.
#include <pybind11/pybind11.h>

namespace pointsurf::python {

/// PointCloud and TriangleMesh: their arrays are numpy views of the C++ vectors (no copy out;
/// the view keeps its owner alive); assignment copies once into the vectors.
void bind_data(pybind11::module_& m);
/// The registry as plain Python data, the stage runner (the GIL released while a stage runs;
/// progress and Ctrl-C polled from the calling thread), and the exception classes.
void bind_stages(pybind11::module_& m);

}  // namespace pointsurf::python
