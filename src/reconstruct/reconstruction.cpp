// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/reconstruction.h"

#include <map>
#include <stdexcept>

namespace pointsurf {
namespace {

// Each method's own counts and figures (ReconstructionStats::counts and figures), in the order
// the method lists them.
struct MethodValues {
  std::string method;
  std::vector<std::string> counts, figures;
};
const std::vector<MethodValues>& method_values() {
  static const std::vector<MethodValues> values = [] {
    const std::vector<std::string> delaunay = {"delaunay_cells", "hull_points", "normal_filtered", "pruned", "open_pieces",
                                               "closed_pieces", "walk_dropped", "rim_peeled", "flipped_pieces", "fill_triangles_removed"};
    std::vector<std::string> crust = delaunay;
    crust.insert(crust.end(), {"poles", "second_delaunay_vertices", "second_delaunay_cells"});
    return std::vector<MethodValues>{
        {"triangulate", {"selected_triangles", "front_triangles", "pinch_triangles_removed", "inserted_points"}, {"local_spacing_mean"}},
        {"cocone", delaunay, {"seconds_delaunay"}},
        {"crust", crust, {"seconds_delaunay"}},
        {"ball-pivot", {"fill_triangles_removed"}, {}},
        {"poisson",
         {"skipped_normals", "depth", "finest_level", "finest_nodes", "trimmed_triangles", "trim_cut_triangles", "trim_removed_islands",
          "unsupported_pieces", "unsupported_triangles"},
         {"iso_value", "peak_megabytes"}},
    };
  }();
  return values;
}

template <class V>
V named_value(const std::vector<std::pair<std::string, V>>& list, const std::string& name) {
  for (const auto& [key, value] : list)
    if (key == name) return value;
  throw std::logic_error("reconstruct: the method reported no \"" + name + "\"");
}

}  // namespace

const ResultTable<ReconstructionStats>& ReconstructionStats::results(const std::string& method) {
  static const std::map<std::string, ResultTable<ReconstructionStats>> tables = [] {
    using S = ReconstructionStats;
    std::map<std::string, ResultTable<S>> out;
    for (const MethodValues& m : method_values()) {
      ResultTable<S>& t = out[m.method];
      t.count("duplicate_points", &S::duplicate_points, "Exact duplicates of earlier points, left unused").as_count();
      t.count("candidate_triangles", &S::candidate_triangles, "Triangles the method proposed before choosing").as_count();
      t.count("holes_filled", &S::holes_filled, "Holes the hole filler closed").as_count();
      t.count("fill_triangles", &S::fill_triangles, "Triangles the hole filler added").as_count();
      for (const std::string& name : m.counts)
        t.computed(name, ResultType::Integer, [name](const S& s) { return ResultValue(std::int64_t(named_value(s.counts, name))); },
                   "A count of the method")
            .as_count();
      for (const std::string& name : m.figures)
        t.computed(name, ResultType::Number, [name](const S& s) { return ResultValue(named_value(s.figures, name)); }, "A figure of the method");
      t.number("method_seconds", &S::seconds, "Wall time of the method").with_unit("seconds");
    }
    return out;
  }();
  const auto it = tables.find(method);
  if (it == tables.end()) throw std::logic_error("ReconstructionStats: no method " + method);
  return it->second;
}

}  // namespace pointsurf
