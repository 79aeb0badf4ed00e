// SPDX-License-Identifier: GPL-3.0-or-later
// STEP and IGES through OpenCASCADE (Debian libocct-data-exchange-dev): the only file of
// pointsurf that includes it.
#include "pointsurf/surface/cad_io.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <mutex>
#include <string>

#include <fmt/format.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESControl_Writer.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <IGESData_IGESWriter.hxx>
#include <IGESSelect_WorkLibrary.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Precision.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <StepData_StepModel.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <UnitsMethods.hxx>

#include "io/detail/file_util.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

// OpenCASCADE's exchange settings (the session's length unit, Interface_Static) are
// process-wide; its messages go to stdout unless its printers are removed (once).
std::mutex& exchange_mutex() {
  static std::mutex m;
  static const bool quiet = [] {
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    return true;
  }();
  (void)quiet;
  return m;
}

// The unit names of OpenCASCADE's "xstep.cascade.unit", "write.step.unit" and IGES.
const char* occt_unit(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Millimetre: return "MM";
    case LengthUnit::Inch: return "INCH";
    case LengthUnit::Metre: break;
  }
  return "M";
}

// The session's length unit (OpenCASCADE keeps it in millimetres).
void set_session_unit(LengthUnit unit) {
  UnitsMethods::SetCasCadeLengthUnit(1000.0 * metres_per(unit), UnitsMethods_LengthUnit_Millimeter);
  Interface_Static::SetCVal("xstep.cascade.unit", occt_unit(unit));
}

std::string display(const std::filesystem::path& file) { return file.string(); }

// The distinct knots and their multiplicities of a clamped knot vector.
void compress_knots(const std::vector<double>& knots, std::vector<double>& values, std::vector<int>& multiplicities) {
  values.clear();
  multiplicities.clear();
  for (const double k : knots) {
    if (!values.empty() && k == values.back()) ++multiplicities.back();
    else values.push_back(k), multiplicities.push_back(1);
  }
}

Handle(Geom_BSplineSurface) to_occt(const BSplineSurface& s) {
  const int nu = s.count_u(), nv = s.count_v();
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Eigen::Vector3d p = s.origin() + s.control(i, j);
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
    }
  std::vector<double> uk, vk;
  std::vector<int> um, vm;
  compress_knots(s.knots_u(), uk, um);
  compress_knots(s.knots_v(), vk, vm);
  TColStd_Array1OfReal ua(1, int(uk.size())), va(1, int(vk.size()));
  TColStd_Array1OfInteger uma(1, int(um.size())), vma(1, int(vm.size()));
  for (std::size_t k = 0; k < uk.size(); ++k) ua.SetValue(int(k) + 1, uk[k]), uma.SetValue(int(k) + 1, um[k]);
  for (std::size_t k = 0; k < vk.size(); ++k) va.SetValue(int(k) + 1, vk[k]), vma.SetValue(int(k) + 1, vm[k]);
  return new Geom_BSplineSurface(poles, ua, va, uma, vma, s.degree_u(), s.degree_v());
}

BSplineSurface from_occt(const Handle(Geom_BSplineSurface)& g) {
  Handle(Geom_BSplineSurface) s = g;
  if (s->IsUPeriodic() || s->IsVPeriodic()) {
    s = Handle(Geom_BSplineSurface)::DownCast(s->Copy());
    if (s->IsUPeriodic()) s->SetUNotPeriodic();
    if (s->IsVPeriodic()) s->SetVNotPeriodic();
  }
  const int nu = s->NbUPoles(), nv = s->NbVPoles();
  std::vector<double> U, V;
  const TColStd_Array1OfReal& us = s->UKnotSequence();
  const TColStd_Array1OfReal& vs = s->VKnotSequence();
  for (int k = us.Lower(); k <= us.Upper(); ++k) U.push_back(us(k));
  for (int k = vs.Lower(); k <= vs.Upper(); ++k) V.push_back(vs(k));
  const gp_Pnt o = s->Pole(1, 1);
  const Eigen::Vector3d origin(o.X(), o.Y(), o.Z());
  std::vector<Eigen::Vector3d> control(std::size_t(nu) * std::size_t(nv));
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const gp_Pnt p = s->Pole(i + 1, j + 1);
      control[std::size_t(i) * std::size_t(nv) + std::size_t(j)] = Eigen::Vector3d(p.X(), p.Y(), p.Z()) - origin;
    }
  return BSplineSurface(s->UDegree(), s->VDegree(), std::move(U), std::move(V), nu, nv, std::move(control), origin);
}

bool unit_weights(const Handle(Geom_BSplineSurface)& s) {
  if (!s->IsURational() && !s->IsVRational()) return true;
  for (int i = 1; i <= s->NbUPoles(); ++i)
    for (int j = 1; j <= s->NbVPoles(); ++j)
      if (std::abs(s->Weight(i, j) - 1.0) > 1e-12) return false;
  return true;
}

}  // namespace

std::string_view length_unit_name(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Millimetre: return "mm";
    case LengthUnit::Inch: return "in";
    case LengthUnit::Metre: break;
  }
  return "m";
}

LengthUnit parse_length_unit(std::string_view name) {
  std::string n(name);
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (n == "m" || n == "metre" || n == "meter" || n == "metres" || n == "meters") return LengthUnit::Metre;
  if (n == "mm" || n == "millimetre" || n == "millimeter" || n == "millimetres" || n == "millimeters") return LengthUnit::Millimetre;
  if (n == "in" || n == "inch" || n == "inches") return LengthUnit::Inch;
  throw UsageError(fmt::format("unit: '{}' is not a length unit; choose m, mm or in", name));
}

double metres_per(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Millimetre: return 0.001;
    case LengthUnit::Inch: return 0.0254;
    case LengthUnit::Metre: break;
  }
  return 1.0;
}

CadFormat cad_format_of(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".step" || ext == ".stp") return CadFormat::Step;
  if (ext == ".igs" || ext == ".iges") return CadFormat::Iges;
  throw UsageError(fmt::format("{}: not a CAD exchange file by its extension; use .step, .stp, .igs or .iges", display(file)));
}

void write_cad(const std::filesystem::path& file, std::span<const BSplineSurface> surfaces, const CadWriteParams& params) {
  const CadFormat format = cad_format_of(file);
  if (surfaces.empty()) throw UsageError(fmt::format("{}: no surfaces to write", display(file)));
  for (std::size_t k = 0; k < surfaces.size(); ++k)
    if (surfaces[k].empty()) throw UsageError(fmt::format("{}: surface {} is empty", display(file), k));
  io::detail::TemporaryOutput out(file);
  const std::lock_guard lock(exchange_mutex());
  try {
    std::vector<TopoDS_Face> faces;
    for (std::size_t k = 0; k < surfaces.size(); ++k) {
      BRepBuilderAPI_MakeFace make(to_occt(surfaces[k]), Precision::Confusion());
      if (!make.IsDone()) throw Error(fmt::format("{}: OpenCASCADE could not make a face of surface {}", display(file), k));
      faces.push_back(make.Face());
    }
    const char* unit = occt_unit(params.unit);
    bool written = false;
    if (format == CadFormat::Step) {
      STEPControl_Writer writer;
      set_session_unit(params.unit);
      Interface_Static::SetCVal("write.step.unit", unit);
      // the shapes' unit and the file's, in millimetres: the same, so nothing is scaled
      writer.Model()->SetLocalLengthUnit(1000.0 * metres_per(params.unit));
      writer.Model()->SetWriteLengthUnit(1000.0 * metres_per(params.unit));
      Interface_Static::SetCVal("write.step.schema", "AP214IS");
      for (const TopoDS_Face& f : faces)
        if (writer.Transfer(f, STEPControl_AsIs) != IFSelect_RetDone)
          throw Error(fmt::format("{}: OpenCASCADE could not translate a face to STEP", display(file)));
      written = writer.Write(out.path().string().c_str()) == IFSelect_RetDone;
    } else {
      set_session_unit(params.unit);
      IGESControl_Writer writer(unit, 0);  // mode 0: faces as trimmed surfaces (entity 144)
      // the shapes' unit, in millimetres: the file's (its header) is the same, nothing is scaled
      IGESData_GlobalSection header = writer.Model()->GlobalSection();
      header.SetCascadeUnit(1000.0 * metres_per(params.unit));
      writer.Model()->SetGlobalSection(header);
      for (const TopoDS_Face& f : faces)
        if (!writer.AddShape(f)) throw Error(fmt::format("{}: OpenCASCADE could not translate a face to IGES", display(file)));
      writer.ComputeModel();
      // IGESControl_Writer::Write with 17 significant digits (its default, 10, moves a point
      // 5e6 m from the origin by up to 0.25 mm): a double is read back as written
      IGESData_IGESWriter printer(writer.Model());
      printer.FloatWriter().SetFormat("%.16E");
      printer.SendModel(IGESSelect_WorkLibrary::DefineProtocol());
      std::ofstream stream(out.path(), std::ios::binary);
      written = stream && printer.Print(stream);
      stream.close();
      written = written && stream;
    }
    if (!written) throw Error(fmt::format("{}: OpenCASCADE could not write the file", display(file)));
  } catch (const Standard_Failure& e) {
    throw Error(fmt::format("{}: OpenCASCADE failed: {}", display(file), e.GetMessageString()));
  }
  out.commit();
}

CadSurfaces read_cad(const std::filesystem::path& file, LengthUnit unit) {
  const CadFormat format = cad_format_of(file);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError(fmt::format("{}: no such file", display(file)));
  CadSurfaces result;
  result.unit = unit;
  const std::lock_guard lock(exchange_mutex());
  try {
    TopoDS_Shape shape;
    if (format == CadFormat::Step) {
      STEPControl_Reader reader;
      set_session_unit(unit);
      if (reader.ReadFile(file.string().c_str()) != IFSelect_RetDone)
        throw InputError(fmt::format("{}: not a readable STEP file", display(file)));
      reader.SetSystemLengthUnit(1000.0 * metres_per(unit));  // needs the model read
      reader.TransferRoots();
      shape = reader.OneShape();
    } else {
      IGESControl_Reader reader;
      set_session_unit(unit);
      if (reader.ReadFile(file.string().c_str()) != IFSelect_RetDone)
        throw InputError(fmt::format("{}: not a readable IGES file", display(file)));
      // the unit the shapes are made in, in millimetres (the file's own unit is in its header)
      const Handle(IGESData_IGESModel) model = Handle(IGESData_IGESModel)::DownCast(reader.Model());
      if (model.IsNull()) throw InputError(fmt::format("{}: not a readable IGES file", display(file)));
      IGESData_GlobalSection header = model->GlobalSection();
      header.SetCascadeUnit(1000.0 * metres_per(unit));
      model->SetGlobalSection(header);
      reader.TransferRoots();
      shape = reader.OneShape();
    }
    for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
      ++result.faces;
      Handle(Geom_Surface) g = BRep_Tool::Surface(TopoDS::Face(ex.Current()));
      if (auto trimmed = Handle(Geom_RectangularTrimmedSurface)::DownCast(g); !trimmed.IsNull()) g = trimmed->BasisSurface();
      const Handle(Geom_BSplineSurface) b = Handle(Geom_BSplineSurface)::DownCast(g);
      if (b.IsNull() || !unit_weights(b)) {
        ++result.skipped;
        continue;
      }
      result.surfaces.push_back(from_occt(b));
    }
  } catch (const Standard_Failure& e) {
    throw InputError(fmt::format("{}: OpenCASCADE failed to read it: {}", display(file), e.GetMessageString()));
  }
  return result;
}

}  // namespace pointsurf
