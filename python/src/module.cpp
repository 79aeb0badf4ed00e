// SPDX-License-Identifier: GPL-3.0-or-later
#include "bindings.h"

PYBIND11_MODULE(_pointsurf, m) {
  m.doc() = "pointsurf's compiled core; use the package pointsurf";
  m.attr("__version__") = POINTSURF_VERSION;
  pointsurf::python::bind_data(m);
  pointsurf::python::bind_stages(m);
}
