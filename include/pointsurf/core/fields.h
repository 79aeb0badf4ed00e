// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Field tables: each Params struct of the library declares its fields once, next to the struct
// (key, member, unit, range or choices, one-line doc; the default is the struct's own). From
// that table come the struct's validate(), the pipeline stage's parameters, the command line's
// options and --help, the Python keyword arguments and docs/stages.md.
//
//   struct OutlierParams {
//     int k = 16;              // neighbours per point
//     double std_ratio = 2.0;
//     static const FieldTable<OutlierParams>& fields();
//     void validate() const { fields().validate(*this, "remove_outliers"); }
//   };
//   const FieldTable<OutlierParams>& OutlierParams::fields() {
//     static const FieldTable<OutlierParams> t = [] {
//       FieldTable<OutlierParams> t;
//       t.integer("k", &OutlierParams::k, "Neighbours per point").at_least(1).unit("points");
//       t.number("std_ratio", &OutlierParams::std_ratio, "Drop above mean + std_ratio x std").positive();
//       return t;
//     }();
//     return t;
//   }
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/length.h"

namespace pointsurf {

/// Parameter types. Vector3 and DoubleList hold their numbers in a std::vector<double>.
enum class ParamType { Bool, Int, Double, String, Choice, ChoiceList, Vector3, DoubleList, Length };

/// Name of a type as the messages and --help spell it ("integer", "number", ...).
const char* param_type_name(ParamType type) noexcept;

/// One parameter value: bool, integer, number, text (String, Choice, ChoiceList as "a,b"),
/// numbers (Vector3, DoubleList) or a length.
using ParamValue = std::variant<bool, std::int64_t, double, std::string, std::vector<double>, Length>;

/// A value as text, the way --help, the summary lines and --set write it (numbers in the
/// shortest form that reads back exactly, lists comma separated, lengths "0.5" or "3sp").
std::string format_value(const ParamValue& value);

/// What a parameter is, without the struct it lives in: what every front end shows.
struct ParamSpec {
  std::string name;                  // key in pipelines, reports and Python; the CLI writes
                                     // it --name-with-dashes
  ParamType type = ParamType::Double;
  ParamValue default_value;          // taken from a default-constructed Params struct
  std::string unit;                  // "cloud units", "degrees", "mean spacings", "" (none)
  double min = -std::numeric_limits<double>::infinity();  // numeric range (Int, Double, lists,
  double max = std::numeric_limits<double>::infinity();   // a length's value in either unit)
  bool min_open = false, max_open = false;  // (min or [min; max) or max]
  std::vector<std::string> choices;  // Choice, ChoiceList
  std::string doc;                   // one line
  std::vector<std::string> methods;  // methods it belongs to; empty: every method
  std::string meta;                  // placeholder in --help ("N", "R", "X,Y,Z")
  std::vector<std::string> old_names;  // keys accepted with a deprecation warning

  bool has_range() const noexcept;
  /// "[3, inf)", "(0, 90]", "" when unbounded.
  std::string range_text() const;
  bool applies_to(const std::string& method) const;

  // Chained setters for declarations: t.number(...).positive().unit("degrees").
  ParamSpec& with_unit(std::string u) { unit = std::move(u); return *this; }
  ParamSpec& with_meta(std::string m) { meta = std::move(m); return *this; }
  ParamSpec& range(double lo, double hi, bool lo_open = false, bool hi_open = false) {
    min = lo; max = hi; min_open = lo_open; max_open = hi_open;
    return *this;
  }
  ParamSpec& at_least(double lo) { return range(lo, std::numeric_limits<double>::infinity()); }
  ParamSpec& positive() { return range(0.0, std::numeric_limits<double>::infinity(), true, false); }
  ParamSpec& non_negative() { return at_least(0.0); }
  ParamSpec& only(std::vector<std::string> m) { methods = std::move(m); return *this; }
  ParamSpec& was(std::string old_key) { old_names.push_back(std::move(old_key)); return *this; }
};

/// Parses `text` as a value of `spec` (the --set and command-line form: "30", "0.5", "true",
/// "mst", "1,2,3", "3sp") and checks it against the range or choices. Throws UsageError with
/// the message "KEY: ..." (KEY = spec.name), e.g. `k: "abc" is not an integer`.
ParamValue parse_param_text(const ParamSpec& spec, const std::string& text);
/// Checks a value of the right type against the range or choices (UsageError "KEY: ...").
void check_param_value(const ParamSpec& spec, const ParamValue& value);
/// The library's form of a range failure: "KEY must be >= 3, got 2" (no prefix), or "" when
/// `value` is within the range and choices of `spec`.
std::string range_failure(const ParamSpec& spec, const ParamValue& value);

/// The candidate closest to `word` by edit distance when it is close enough to be a typo
/// (at most a third of its length, at least 1, and at most 3 edits), else "".
std::string closest_name(std::string_view word, const std::vector<std::string>& candidates);

/// The names of an enum's values, one table per enum, used by every field of that type.
template <class E>
struct EnumNames {
  std::vector<std::pair<E, std::string>> entries;

  const std::string& name(E value) const {
    for (const auto& [v, n] : entries)
      if (v == value) return n;
    static const std::string none;
    return none;
  }
  /// The value named `name`; `fallback` when none is (the caller has checked the choices).
  E value(std::string_view name, E fallback = E{}) const {
    for (const auto& [v, n] : entries)
      if (n == name) return v;
    return fallback;
  }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : entries) out.push_back(e.second);
    return out;
  }
};

/// One field of a Params struct: its spec, how to read and write it in a struct, when it is
/// used (validate() checks a field only where it applies) and which member holds it.
template <class P>
struct Field {
  ParamSpec spec;
  std::function<ParamValue(const P&)> get;
  std::function<void(P&, const ParamValue&)> set;
  std::function<bool(const P&)> applies;  // empty: always
  std::size_t member_offset = 0;          // byte offset of the struct member that holds it
  bool exposed = true;                    // false: a library setting no stage offers

  // Chained setters for declarations.
  Field& unit(std::string u) { spec.unit = std::move(u); return *this; }
  Field& meta(std::string m) { spec.meta = std::move(m); return *this; }
  Field& range(double lo, double hi, bool lo_open = false, bool hi_open = false) { spec.range(lo, hi, lo_open, hi_open); return *this; }
  Field& at_least(double lo) { spec.at_least(lo); return *this; }
  Field& positive() { spec.positive(); return *this; }
  Field& non_negative() { spec.non_negative(); return *this; }
  Field& when(std::function<bool(const P&)> condition) { applies = std::move(condition); return *this; }
  Field& internal() { exposed = false; return *this; }
  Field& was(std::string old_key) { spec.was(std::move(old_key)); return *this; }
};

namespace detail {
template <class P, class M>
std::size_t member_offset_of(M P::*member) {
  static const P probe{};
  return static_cast<std::size_t>(reinterpret_cast<const char*>(&(probe.*member)) - reinterpret_cast<const char*>(&probe));
}
}  // namespace detail

/// The field table of a Params struct P.
template <class P>
class FieldTable {
public:
  using value_type = Field<P>;

  Field<P>& boolean(std::string key, bool P::*m, std::string doc) {
    return add(std::move(key), ParamType::Bool, m, std::move(doc), [m](const P& p) { return ParamValue(p.*m); },
               [m](P& p, const ParamValue& v) { p.*m = std::get<bool>(v); });
  }
  template <class I>
    requires std::is_integral_v<I>
  Field<P>& integer(std::string key, I P::*m, std::string doc) {
    auto& f = add(std::move(key), ParamType::Int, m, std::move(doc), [m](const P& p) { return ParamValue(static_cast<std::int64_t>(p.*m)); },
                  [m](P& p, const ParamValue& v) { p.*m = static_cast<I>(std::get<std::int64_t>(v)); });
    if constexpr (std::is_unsigned_v<I>) f.at_least(0.0);
    return f.meta("N");
  }
  Field<P>& number(std::string key, double P::*m, std::string doc) {
    return add(std::move(key), ParamType::Double, m, std::move(doc), [m](const P& p) { return ParamValue(p.*m); },
               [m](P& p, const ParamValue& v) { p.*m = std::get<double>(v); })
        .meta("X");
  }
  Field<P>& text(std::string key, std::string P::*m, std::string doc) {
    return add(std::move(key), ParamType::String, m, std::move(doc), [m](const P& p) { return ParamValue(p.*m); },
               [m](P& p, const ParamValue& v) { p.*m = std::get<std::string>(v); })
        .meta("TEXT");
  }
  Field<P>& length(std::string key, Length P::*m, std::string doc) {
    return add(std::move(key), ParamType::Length, m, std::move(doc), [m](const P& p) { return ParamValue(p.*m); },
               [m](P& p, const ParamValue& v) { p.*m = std::get<Length>(v); })
        .meta("L|Nsp");
  }
  Field<P>& vector3(std::string key, Eigen::Vector3d P::*m, std::string doc) {
    return add(std::move(key), ParamType::Vector3, m, std::move(doc),
               [m](const P& p) { return ParamValue(std::vector<double>{(p.*m).x(), (p.*m).y(), (p.*m).z()}); },
               [m](P& p, const ParamValue& v) {
                 const auto& n = std::get<std::vector<double>>(v);
                 p.*m = Eigen::Vector3d(n[0], n[1], n[2]);
               })
        .meta("X,Y,Z");
  }
  Field<P>& numbers(std::string key, std::vector<double> P::*m, std::string doc) {
    return add(std::move(key), ParamType::DoubleList, m, std::move(doc), [m](const P& p) { return ParamValue(p.*m); },
               [m](P& p, const ParamValue& v) { p.*m = std::get<std::vector<double>>(v); })
        .meta("A,B,...");
  }
  /// An enum member, named by `names` (the enum's one name table).
  template <class E>
    requires std::is_enum_v<E>
  Field<P>& choice(std::string key, E P::*m, const EnumNames<E>& names, std::string doc) {
    auto& f = add(std::move(key), ParamType::Choice, m, std::move(doc), [m, &names](const P& p) { return ParamValue(names.name(p.*m)); },
                  [m, &names](P& p, const ParamValue& v) { p.*m = names.value(std::get<std::string>(v), p.*m); });
    f.spec.choices = names.names();
    return f.meta(join_choices(f.spec.choices));
  }
  /// A list of enum values ("plane,sphere").
  template <class E>
    requires std::is_enum_v<E>
  Field<P>& choices(std::string key, std::vector<E> P::*m, const EnumNames<E>& names, std::string doc) {
    auto& f = add(std::move(key), ParamType::ChoiceList, m, std::move(doc),
                  [m, &names](const P& p) {
                    std::string out;
                    for (E e : p.*m) out += (out.empty() ? "" : ",") + names.name(e);
                    return ParamValue(out);
                  },
                  [m, &names](P& p, const ParamValue& v) {
                    std::vector<E> list;
                    const std::string& s = std::get<std::string>(v);
                    std::size_t start = 0;
                    while (start <= s.size()) {
                      const std::size_t end = std::min(s.find(',', start), s.size());
                      if (end > start) list.push_back(names.value(std::string_view(s).substr(start, end - start)));
                      start = end + 1;
                    }
                    p.*m = std::move(list);
                  });
    f.spec.choices = names.names();
    return f.meta(join_choices(f.spec.choices) + ",...");
  }
  /// A member of any type with its own codec: `get` writes it as a ParamValue of `type`, `set`
  /// reads it back (sizes "WxH", a flag stored as a string...).
  template <class M>
  Field<P>& custom(std::string key, M P::*m, ParamType type, std::string doc, std::function<ParamValue(const M&)> get,
                   std::function<void(M&, const ParamValue&)> set) {
    return add(std::move(key), type, m, std::move(doc), [m, get](const P& p) { return get(p.*m); },
               [m, set](P& p, const ParamValue& v) { set(p.*m, v); });
  }
  /// The fields of a member struct S, through `m`, with keys prefixed by `prefix` ("icp_").
  /// Their conditions still see the inner struct.
  template <class S>
  void nested(S P::*m, const FieldTable<S>& inner, const std::string& prefix = "") {
    const std::size_t offset = detail::member_offset_of(m);
    for (const Field<S>& f : inner.fields()) {
      Field<P> g;
      g.spec = f.spec;
      g.spec.name = prefix + f.spec.name;
      g.get = [m, get = f.get](const P& p) { return get(p.*m); };
      g.set = [m, set = f.set](P& p, const ParamValue& v) { set(p.*m, v); };
      if (f.applies) g.applies = [m, a = f.applies](const P& p) { return a(p.*m); };
      g.member_offset = offset;
      g.exposed = f.exposed;
      fields_.push_back(std::move(g));
    }
  }

  const std::vector<Field<P>>& fields() const noexcept { return fields_; }
  auto begin() const noexcept { return fields_.begin(); }
  auto end() const noexcept { return fields_.end(); }
  std::size_t size() const noexcept { return fields_.size(); }
  const Field<P>* find(std::string_view key) const {
    for (const Field<P>& f : fields_)
      if (f.spec.name == key) return &f;
    return nullptr;
  }

  /// The specs of the exposed fields, defaults read from `defaults`.
  std::vector<ParamSpec> specs(const P& defaults = P{}) const {
    std::vector<ParamSpec> out;
    for (const Field<P>& f : fields_) {
      if (!f.exposed) continue;
      ParamSpec s = f.spec;
      s.default_value = f.get(defaults);
      out.push_back(std::move(s));
    }
    return out;
  }

  /// Throws UsageError "FUNCTION: KEY must be ..., got ..." for the first field that applies
  /// and is out of its range or choices.
  void validate(const P& p, std::string_view function) const {
    for (const Field<P>& f : fields_) {
      if (f.applies && !f.applies(p)) continue;
      const std::string failure = range_failure(f.spec, f.get(p));
      if (!failure.empty()) throw_usage(function, failure, f.spec.name);
    }
  }

private:
  static std::string join_choices(const std::vector<std::string>& c) {
    std::string out;
    for (const std::string& s : c) out += (out.empty() ? "" : "|") + s;
    return out;
  }
  [[noreturn]] static void throw_usage(std::string_view function, const std::string& failure, const std::string& key);

  template <class M>
  Field<P>& add(std::string key, ParamType type, M P::*m, std::string doc, std::function<ParamValue(const P&)> get,
                std::function<void(P&, const ParamValue&)> set) {
    Field<P> f;
    f.spec.name = std::move(key);
    f.spec.type = type;
    f.spec.doc = std::move(doc);
    f.get = std::move(get);
    f.set = std::move(set);
    f.member_offset = detail::member_offset_of(m);
    fields_.push_back(std::move(f));
    return fields_.back();
  }

  std::vector<Field<P>> fields_;
};

namespace detail {
[[noreturn]] void throw_field_usage(std::string_view function, const std::string& failure, const std::string& key);
}

template <class P>
void FieldTable<P>::throw_usage(std::string_view function, const std::string& failure, const std::string& key) {
  detail::throw_field_usage(function, failure, key);
}

/// Number of members of an aggregate P (the completeness test of field tables compares it with
/// the members a table names).
namespace detail {
struct AnyMember {
  template <class T>
  constexpr operator T() const noexcept;  // NOLINT(google-explicit-constructor): declared only
};
template <class P, std::size_t... I>
constexpr bool constructible_with(std::index_sequence<I...>) {
  return requires { P{(void(I), AnyMember{})...}; };
}
template <class P, std::size_t N = 0>
constexpr std::size_t aggregate_member_count() {
  if constexpr (N > 64) return N;
  else if constexpr (!constructible_with<P>(std::make_index_sequence<N + 1>{})) return N;
  else return aggregate_member_count<P, N + 1>();
}
}  // namespace detail

/// How many distinct members of P its table names.
template <class P>
std::size_t members_named(const FieldTable<P>& table) {
  std::vector<std::size_t> offsets;
  for (const Field<P>& f : table) offsets.push_back(f.member_offset);
  std::sort(offsets.begin(), offsets.end());
  return static_cast<std::size_t>(std::unique(offsets.begin(), offsets.end()) - offsets.begin());
}

}  // namespace pointsurf
