// SPDX-License-Identifier: GPL-3.0-or-later
// PointCloud and TriangleMesh for Python. Going out, every attribute is a numpy array over the
// C++ vector's memory, with the Python object as its base (it stays alive while a view does).
// Coming in, an array is copied once, in place when the size is unchanged so earlier views stay
// valid; an assignment that changes the size reallocates, and views taken before it must not be
// used (documented in docs/python.md).
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"

namespace py = pybind11;

namespace pointsurf::python {
namespace {

/// An N x 3 view of a vector of 3-vectors (Vector3d, Vector3f, Triangle), based on `owner`.
template <class Vec>
py::array view_rows(std::vector<Vec>& rows, py::handle owner) {
  using Scalar = typename Vec::Scalar;
  static_assert(sizeof(Vec) == 3 * sizeof(Scalar), "rows are packed");
  const py::ssize_t n = static_cast<py::ssize_t>(rows.size());
  if (n == 0) return py::array_t<Scalar>(std::vector<py::ssize_t>{0, 3});
  return py::array_t<Scalar>({n, py::ssize_t(3)}, {py::ssize_t(sizeof(Vec)), py::ssize_t(sizeof(Scalar))},
                             rows.front().data(), owner);
}

py::array view_values(std::vector<double>& values, py::handle owner) {
  if (values.empty()) return py::array_t<double>(0);
  return py::array_t<double>({py::ssize_t(values.size())}, {py::ssize_t(sizeof(double))}, values.data(), owner);
}

/// Copies an N x 3 array (None or an empty array clears) into `rows`; in place when N is unchanged.
template <class Vec>
void assign_rows(std::vector<Vec>& rows, const py::object& value, const char* what) {
  using Scalar = typename Vec::Scalar;
  if (value.is_none()) {
    rows.clear();
    return;
  }
  auto a = py::array_t<Scalar, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) throw UsageError(std::string(what) + ": expected an N x 3 array of numbers");
  if (a.size() == 0) {
    rows.clear();
    return;
  }
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw UsageError(std::string(what) + ": expected an N x 3 array, got shape " + std::string(py::str(value.attr("shape"))));
  rows.resize(static_cast<std::size_t>(a.shape(0)));
  std::memcpy(static_cast<void*>(rows.data()), a.data(), static_cast<std::size_t>(a.size()) * sizeof(Scalar));
}

void assign_values(std::vector<double>& values, const py::object& value, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 1) throw UsageError(what + ": expected a 1-D array of numbers");
  values.resize(static_cast<std::size_t>(a.shape(0)));
  if (!values.empty()) std::memcpy(values.data(), a.data(), values.size() * sizeof(double));
}

/// A read-write property `name` over a vector of rows of the owner (a member pointer, or a
/// function of the owner that returns the vector): a view going out, a copy coming in.
template <class Owner, class Rows>
void def_rows(py::class_<Owner>& cls, const char* name, Rows rows, const char* doc) {
  cls.def_property(
      name, [rows](py::object self) { return view_rows(std::invoke(rows, self.cast<Owner&>()), self); },
      [rows, name](Owner& o, const py::object& v) { assign_rows(std::invoke(rows, o), v, name); }, doc);
}

py::dict field_views(FieldSet& fields, py::handle owner) {
  py::dict out;
  for (ScalarField& f : fields) out[py::str(f.name)] = view_values(f.values, owner);
  return out;
}

void set_field(FieldSet& fields, const std::string& name, const py::object& value, std::size_t expected, const char* of) {
  std::vector<double> values;
  assign_values(values, value, "field " + name);
  if (values.size() != expected)
    throw UsageError("field " + name + ": " + std::to_string(values.size()) + " values for " + std::to_string(expected) + " " + of);
  ScalarField& f = fields.add(name, expected);
  f.values = std::move(values);
}

}  // namespace

void bind_data(py::module_& m) {
  py::class_<PointCloud> cloud(m, "PointCloud", py::dynamic_attr(),
                         "Points with optional normals, colours (RGB in [0, 1]) and named scalar fields.\n"
                         "Attributes are numpy views of the C++ memory (no copy); assigning copies once.");
  cloud.def(py::init([](const py::object& positions, const py::object& normals, const py::object& colors, const py::dict& fields) {
             PointCloud c;
             assign_rows(c.positions, positions, "positions");
             assign_rows(c.normals, normals, "normals");
             assign_rows(c.colors, colors, "colors");
             for (auto [name, value] : fields)
               set_field(c.fields, py::cast<std::string>(name), py::reinterpret_borrow<py::object>(value), c.size(), "points");
             c.validate();
             return c;
           }),
           py::arg("positions") = py::none(), py::arg("normals") = py::none(), py::arg("colors") = py::none(),
           py::arg("fields") = py::dict());
  def_rows(cloud, "positions", &PointCloud::positions, "N x 3 float64");
  def_rows(cloud, "normals", &PointCloud::normals, "N x 3 float64, or 0 x 3");
  def_rows(cloud, "colors", &PointCloud::colors, "N x 3 float32 in [0, 1], or 0 x 3");
  cloud
      .def_property_readonly("fields", [](py::object self) { return field_views(self.cast<PointCloud&>().fields, self); },
                             "{name: N float64 view}")
      .def("set_field", [](PointCloud& c, const std::string& name, const py::object& v) { set_field(c.fields, name, v, c.size(), "points"); },
           py::arg("name"), py::arg("values"))
      .def("remove_field", [](PointCloud& c, const std::string& name) { return c.fields.remove(name); }, py::arg("name"))
      .def("copy", [](const PointCloud& c) { return c; })
      .def("validate", &PointCloud::validate)
      .def("__len__", &PointCloud::size)
      .def("__repr__", [](const PointCloud& c) {
        std::string fields;
        for (const ScalarField& f : c.fields) fields += (fields.empty() ? "" : ", ") + f.name;
        return "PointCloud(" + std::to_string(c.size()) + " points" + (c.has_normals() ? ", normals" : "") +
               (c.has_colors() ? ", colors" : "") + (fields.empty() ? "" : ", fields: " + fields) + ")";
      });

  py::class_<TriangleMesh> mesh(m, "TriangleMesh", py::dynamic_attr(),
                           "Vertices, triangles (int32 indices, counter-clockwise from outside), optional vertex\n"
                           "normals, colours, vertex and face fields; numpy views of the C++ memory.");
  mesh.def(py::init([](const py::object& vertices, const py::object& triangles, const py::object& normals, const py::object& colors) {
             TriangleMesh t;
             assign_rows(t.vertices.positions, vertices, "vertices");
             assign_rows(t.triangles, triangles, "triangles");
             assign_rows(t.vertices.normals, normals, "vertex_normals");
             assign_rows(t.vertices.colors, colors, "vertex_colors");
             t.validate();
             return t;
           }),
           py::arg("vertices") = py::none(), py::arg("triangles") = py::none(), py::arg("vertex_normals") = py::none(),
           py::arg("vertex_colors") = py::none());
  const auto positions = [](TriangleMesh& t) -> std::vector<Vector3d>& { return t.vertices.positions; };
  def_rows(mesh, "vertices", positions, "V x 3 float64");
  def_rows(mesh, "positions", positions, "the vertices");
  def_rows(mesh, "triangles", &TriangleMesh::triangles, "F x 3 int32");
  def_rows(mesh, "vertex_normals", [](TriangleMesh& t) -> std::vector<Vector3d>& { return t.vertices.normals; }, "V x 3 float64, or 0 x 3");
  def_rows(mesh, "vertex_colors", [](TriangleMesh& t) -> std::vector<Vector3f>& { return t.vertices.colors; }, "V x 3 float32 in [0, 1], or 0 x 3");
  mesh
      .def_property_readonly("vertex_fields", [](py::object self) { return field_views(self.cast<TriangleMesh&>().vertices.fields, self); })
      .def_property_readonly("face_fields", [](py::object self) { return field_views(self.cast<TriangleMesh&>().face_fields, self); })
      .def("set_vertex_field", [](TriangleMesh& t, const std::string& name, const py::object& v) { set_field(t.vertices.fields, name, v, t.vertex_count(), "vertices"); },
           py::arg("name"), py::arg("values"))
      .def("set_face_field", [](TriangleMesh& t, const std::string& name, const py::object& v) { set_field(t.face_fields, name, v, t.triangle_count(), "triangles"); },
           py::arg("name"), py::arg("values"))
      .def("vertex_cloud", [](const TriangleMesh& t) { return t.vertices; }, "The vertices with their attributes as a PointCloud (a copy).")
      .def("copy", [](const TriangleMesh& t) { return t; })
      .def("validate", &TriangleMesh::validate)
      .def("__repr__", [](const TriangleMesh& t) {
        return "TriangleMesh(" + std::to_string(t.vertex_count()) + " vertices, " + std::to_string(t.triangle_count()) + " triangles)";
      });
}

}  // namespace pointsurf::python
