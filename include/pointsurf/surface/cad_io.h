// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// B-spline surfaces to and from CAD exchange files (STEP, IGES) through OpenCASCADE.
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pointsurf/surface/bspline_surface.h"

namespace pointsurf {

/// The length unit of a cloud's coordinates, written into the file (and read back from it).
enum class LengthUnit { Metre, Millimetre, Inch };

/// "m", "mm", "in"; parse_length_unit() also takes "metre", "meter", "millimetre", "millimeter",
/// "inch" and throws UsageError naming the choices otherwise.
std::string_view length_unit_name(LengthUnit unit);
LengthUnit parse_length_unit(std::string_view name);
/// Metres in one `unit` (1, 0.001, 0.0254).
double metres_per(LengthUnit unit);

/// CAD exchange formats, chosen by the file's extension: .step / .stp (STEP AP214) and
/// .igs / .iges (IGES 5.3).
enum class CadFormat { Step, Iges };
/// The format of `file` by its extension; throws UsageError naming the extensions otherwise.
CadFormat cad_format_of(const std::filesystem::path& file);

struct CadWriteParams {
  /// The unit of the surfaces' coordinates, and the unit the file declares: control points are
  /// written as they are, not scaled.
  LengthUnit unit = LengthUnit::Metre;
};

/// Writes each surface as one face bounded by its parameter domain (four edges on the
/// iso-parameter lines u_min, u_max, v_min, v_max): a STEP ADVANCED_FACE over a
/// B_SPLINE_SURFACE_WITH_KNOTS, or an IGES trimmed surface (entity 144) of a rational B-spline
/// surface (entity 128) with weights 1. Control points, knots and degrees are written exactly as
/// the surface holds them, in the input's coordinates (the surface's origin added back).
/// The file is written to a temporary file next to it and renamed: it is whole or absent.
/// Throws UsageError for an unknown extension, no surfaces or an empty surface, and Error when
/// OpenCASCADE cannot build a face or write the file. Thread-safe (OpenCASCADE's exchange
/// settings are global: calls are serialised).
void write_cad(const std::filesystem::path& file, std::span<const BSplineSurface> surfaces, const CadWriteParams& params = {});

/// What read_cad found.
struct CadSurfaces {
  std::vector<BSplineSurface> surfaces;  // in `unit`; origin at each surface's first control point
  LengthUnit unit = LengthUnit::Metre;   // the unit the coordinates were converted to
  std::size_t faces = 0;                 // faces in the file
  std::size_t skipped = 0;               // faces whose surface is not a non-rational B-spline
};

/// Reads the faces of a STEP or IGES file and returns their underlying B-spline surfaces
/// (the natural domain; trimming curves are not read), converted to `unit`. Faces whose
/// surface is not a B-spline with unit weights (planes, cylinders, NURBS) are counted in
/// `skipped`. Throws InputError naming the file when it cannot be read.
CadSurfaces read_cad(const std::filesystem::path& file, LengthUnit unit = LengthUnit::Metre);

}  // namespace pointsurf
