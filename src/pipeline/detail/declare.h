// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Helpers that keep each stage's declaration short: P::integer("k", NormalParams{}.k, "doc")
//   .at_least(3).unit("points").only({"sor"}).
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/pipeline/registry.h"
#include "pointsurf/pipeline/stage.h"

namespace pointsurf::detail {

class P {
public:
  static P boolean(std::string name, bool value, std::string doc) { return P(std::move(name), ParamType::Bool, value, std::move(doc)); }
  static P integer(std::string name, std::int64_t value, std::string doc) {
    return P(std::move(name), ParamType::Int, value, std::move(doc)).meta("N");
  }
  static P number(std::string name, double value, std::string doc) {
    return P(std::move(name), ParamType::Double, value, std::move(doc)).meta("X");
  }
  static P text(std::string name, std::string value, std::string doc) {
    return P(std::move(name), ParamType::String, std::move(value), std::move(doc)).meta("TEXT");
  }
  static P choice(std::string name, std::string value, std::vector<std::string> choices, std::string doc) {
    P p(std::move(name), ParamType::Choice, std::move(value), std::move(doc));
    p.spec_.choices = std::move(choices);
    std::string meta;
    for (const std::string& c : p.spec_.choices) meta += (meta.empty() ? "" : "|") + c;
    return p.meta(meta);
  }
  static P vector3(std::string name, std::vector<double> value, std::string doc) {
    return P(std::move(name), ParamType::Vector3, std::move(value), std::move(doc)).meta("X,Y,Z");
  }
  static P numbers(std::string name, std::vector<double> value, std::string doc) {
    return P(std::move(name), ParamType::DoubleList, std::move(value), std::move(doc)).meta("A,B,...");
  }

  P& unit(std::string u) { spec_.unit = std::move(u); return *this; }
  P& meta(std::string m) { spec_.meta = std::move(m); return *this; }
  P& only(std::vector<std::string> methods) { spec_.methods = std::move(methods); return *this; }
  P& range(double lo, double hi, bool lo_open = false, bool hi_open = false) {
    spec_.min = lo; spec_.max = hi; spec_.min_open = lo_open; spec_.max_open = hi_open;
    return *this;
  }
  P& at_least(double lo) { return range(lo, std::numeric_limits<double>::infinity()); }
  P& positive() { return range(0.0, std::numeric_limits<double>::infinity(), true, false); }
  P& non_negative() { return at_least(0.0); }
  operator ParamSpec() && { return std::move(spec_); }  // NOLINT(google-explicit-constructor)
  operator ParamSpec() const& { return spec_; }         // NOLINT(google-explicit-constructor)

private:
  P(std::string name, ParamType type, ParamValue value, std::string doc) {
    spec_.name = std::move(name);
    spec_.type = type;
    spec_.default_value = std::move(value);
    spec_.doc = std::move(doc);
  }
  ParamSpec spec_;
};

inline std::vector<double> as_list(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

/// A stage's parameters from a library field table (core/fields.h): the exposed fields, their
/// defaults read from `defaults`, restricted to `methods` when given.
template <class Params>
std::vector<ParamSpec> params_of(const FieldTable<Params>& table, const std::vector<std::string>& methods = {},
                                 const Params& defaults = Params{}) {
  std::vector<ParamSpec> specs = table.specs(defaults);
  for (ParamSpec& s : specs) s.methods = methods;
  return specs;
}

/// The library's Params from a stage's resolved arguments: every exposed field the stage
/// declares (given or default) is set; the others keep `p`'s values.
template <class Params>
Params read_params(const StageArgs& args, Params p = Params{}, const FieldTable<Params>& table = Params::fields()) {
  for (const Field<Params>& f : table)
    if (f.exposed && args.has(f.spec.name)) f.set(p, args.value(f.spec.name));
  return p;
}

/// Appends `more` to `specs`.
inline void append(std::vector<ParamSpec>& specs, std::vector<ParamSpec> more) {
  for (ParamSpec& s : more) specs.push_back(std::move(s));
}

// The stage declarations, one function per stage (src/pipeline/stage_*.cpp).
StageSpec read_stage();
StageSpec write_stage();
StageSpec crop_stage();
StageSpec range_stage();
StageSpec transform_stage();
StageSpec merge_stage();
StageSpec clean_stage();
StageSpec simplify_stage();
StageSpec normals_stage();
StageSpec curvature_stage();
StageSpec features_stage();
StageSpec segment_stage();
StageSpec boundary_stage();
StageSpec reconstruct_stage();
StageSpec quality_stage();
StageSpec evaluate_stage();
StageSpec render_stage();
StageSpec register_stage();
StageSpec register_many_stage();

}  // namespace pointsurf::detail

namespace pointsurf::detail {
/// PCA normals over `k` neighbours, MST-oriented, for a stage whose input has none (said in
/// its record's warnings); uses the context's tree of run.output.
void estimate_missing_normals(StageRun& run, int k, const ProgressCallback& progress);
/// For a stage that uses the normals the input came with: throws InputError when every one of
/// them is (0,0,0) or not finite (an estimate whose neighbourhoods were too small), and warns
/// with the count and share of such points otherwise, saying what the stage does with them
/// (`skipped`, e.g. "not moved"). Returns that count.
std::size_t check_input_normals(StageRun& run, const std::string& skipped);
/// The count check_input_normals records ("zero_normals"), for the declarations of the stages
/// that call it.
std::vector<ResultSpec> zero_normals_specs();
}  // namespace pointsurf::detail
