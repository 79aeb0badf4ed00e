// SPDX-License-Identifier: GPL-3.0-or-later
// The registry as Python data, and one runner for every stage and for whole pipelines.
//
// A stage call is checked exactly as the command line checks it: its values arrive as text
// (the --set form) and go through build_pipeline, so Python gets the CLI's messages. The step
// is built behind placeholder readers (one per input) and, where needed, a placeholder writer,
// then run alone over a Context holding copies of the inputs (the inputs stay unchanged).
//
// Threads: the stage runs on a worker thread with the GIL released. The calling thread waits,
// taking the GIL every 50 ms to run Python's signal handlers (Ctrl-C), which cancels the stage
// at its next progress report. A user progress callback is called from the reporting thread
// with the GIL taken for the call only, at most every 20 ms (and at the end).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <array>
#include <exception>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/pipeline/pipeline.h"
#include "pointsurf/pipeline/registry.h"

namespace py = pybind11;

namespace pointsurf::python {
namespace {

const char* kind_name(DataKind kind) {
  switch (kind) {
    case DataKind::Cloud: return "cloud";
    case DataKind::Mesh: return "mesh";
    case DataKind::Any: return "any";
  }
  return "any";
}

py::dict param_dict(const ParamSpec& p) {
  py::dict d;
  d["name"] = p.name;
  d["type"] = param_type_name(p.type);
  d["kind"] = static_cast<int>(p.type);
  // A length's default is its text ("3sp"); the other types map to Python values as they are.
  d["default"] = std::visit(
      [](const auto& v) -> py::object {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, Length>) return py::str(v.text());
        else return py::cast(v);
      },
      p.default_value);
  d["unit"] = p.unit;
  d["min"] = p.min;
  d["max"] = p.max;
  d["range"] = p.range_text();
  d["choices"] = p.choices;
  d["doc"] = p.doc;
  d["methods"] = p.methods;
  d["meta"] = p.meta;
  return d;
}

py::list stage_list() {
  py::list out;
  for (const StageSpec& s : registered_stages()) {
    py::dict d;
    d["name"] = s.name;
    d["summary"] = s.summary;
    d["description"] = s.description;
    py::list consumes;
    for (const Slot& slot : s.consumes) consumes.append(py::make_tuple(slot.name, kind_name(slot.kind)));
    d["consumes"] = consumes;
    d["produces"] = s.produces ? py::object(py::str(kind_name(s.produces->kind))) : py::object(py::none());
    d["methods"] = s.methods;
    d["default_method"] = s.default_method;
    d["method_list"] = s.method_list;
    d["shape"] = command_shape_name(s.shape);
    d["measures"] = s.measures();
    d["writes_param"] = s.writes_param;
    py::list results;  // the declared counts and metrics of the report (core/results.h)
    for (const ResultSpec& r : s.results) {
      py::dict m;
      m["key"] = r.key;
      m["block"] = result_block_name(r.block);
      m["type"] = result_type_name(r.type);
      m["unit"] = r.unit;
      m["better"] = better_name(r.better);
      m["doc"] = r.doc;
      results.append(m);
    }
    d["results"] = results;
    d["examples"] = s.examples;
    py::list params;
    for (const ParamSpec& p : s.params) params.append(param_dict(p));
    d["params"] = params;
    out.append(d);
  }
  return out;
}

DataItem to_item(const py::handle& obj) {
  DataItem item;
  if (py::isinstance<PointCloud>(obj)) {
    item.cloud() = obj.cast<const PointCloud&>();
    item.cloud().validate();
  } else if (py::isinstance<TriangleMesh>(obj)) {
    TriangleMesh mesh = obj.cast<const TriangleMesh&>();
    mesh.validate();
    item.assign_mesh(std::move(mesh), "python");
  } else {
    throw UsageError(fmt::format("expected a PointCloud or a TriangleMesh, got {}", std::string(py::str(obj.get_type().attr("__name__")))));
  }
  return item;
}

py::object from_item(DataItem&& item) {
  if (!item.is_mesh) return py::cast(std::move(item.cloud()));
  return py::cast(std::move(item.mesh));
}

/// Progress and cancellation shared by the worker, the library's threads and the waiting caller.
class Watch {
public:
  explicit Watch(py::object callback) : callback_(std::move(callback)) {}

  /// The library's progress hook: false cancels the stage.
  bool report(double fraction) {
    if (stop_.load()) return false;
    if (callback_.is_none()) return true;
    {
      std::lock_guard lock(mutex_);
      const auto now = std::chrono::steady_clock::now();
      if (fraction < 1.0 && now - last_ < std::chrono::milliseconds(20)) return true;
      last_ = now;
    }
    py::gil_scoped_acquire gil;
    try {
      py::object answer = callback_(fraction);
      if (!answer.is_none() && !answer.cast<bool>()) stop(Why::Callback);
    } catch (py::error_already_set& e) {
      std::lock_guard lock(mutex_);
      if (!error_) error_.emplace(std::move(e));
      stop(Why::Raised);
    }
    return !stop_.load();
  }

  /// Runs `work` on a worker thread; the caller (holding the GIL) waits with it released,
  /// polling Python's signal handlers. Rethrows the work's exception, or the Python one that
  /// stopped it (KeyboardInterrupt, the callback's own).
  void run(const std::function<void()>& work) {
    std::exception_ptr failure;
    bool done = false;
    std::mutex m;
    std::condition_variable cv;
    {
      py::gil_scoped_release release;
      std::thread worker([&] {
        try {
          work();
        } catch (...) {
          failure = std::current_exception();
        }
        std::lock_guard lock(m);
        done = true;
        cv.notify_all();
      });
      std::unique_lock lock(m);
      while (!cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
        lock.unlock();
        {
          py::gil_scoped_acquire gil;
          if (PyErr_CheckSignals() != 0) {
            std::lock_guard elock(mutex_);
            if (!error_) error_.emplace();  // fetches KeyboardInterrupt (or what the handler raised)
            stop(Why::Raised);
          }
        }
        lock.lock();
      }
      lock.unlock();
      worker.join();
    }
    if (why_ == Why::Raised && error_) throw std::move(*error_);
    if (failure) {
      if (why_ == Why::Callback) {
        try {
          std::rethrow_exception(failure);
        } catch (ComputeError& e) {
          if (e.kind() == ErrorKind::Cancelled) throw;
          throw CancelledError(e.message(), e.place());  // a stage that reworded its cancel
        }
      }
      std::rethrow_exception(failure);
    }
  }

  ProgressCallback hook() {
    return [this](double f) { return report(f); };
  }

private:
  enum class Why { None, Callback, Raised };
  void stop(Why why) {
    if (!stop_.exchange(true)) why_ = why;
  }
  py::object callback_;
  std::atomic<bool> stop_{false};
  Why why_ = Why::None;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_{};
  std::optional<py::error_already_set> error_;
};

// Python's classes for the library's errors, by kind (bind_stages creates them).
std::array<PyObject*, 4> error_classes{};
py::handle error_class(ErrorKind kind) { return error_classes[static_cast<std::size_t>(kind)]; }

/// Raises `e` in Python as its kind's class with message `text` and the error's data as
/// attributes, None where unknown: kind, stage, stage_index, key, file, offset, message (see
/// core/error.h). `place` is the place as the caller should see it.
[[noreturn]] void raise_python(const Error& e, const ErrorPlace& place, const std::string& text) {
  const py::handle cls = error_class(e.kind());
  py::object instance = cls(text);
  const auto text_or_none = [](const std::string& s) -> py::object { return s.empty() ? py::object(py::none()) : py::object(py::str(s)); };
  instance.attr("kind") = error_kind_name(e.kind());
  instance.attr("stage") = text_or_none(place.stage);
  instance.attr("stage_index") = place.stage_index == 0 ? py::object(py::none()) : py::object(py::int_(place.stage_index));
  instance.attr("key") = text_or_none(place.key);
  instance.attr("file") = text_or_none(place.file);
  instance.attr("offset") = text_or_none(place.offset);
  instance.attr("message") = e.message();
  PyErr_SetObject(cls.ptr(), instance.ptr());
  throw py::error_already_set();
}

/// Runs `f`; an error of the one-stage pipeline is raised in the function's words:
/// "TYPE: MESSAGE" (the stage's position and the pipeline's origin mean nothing to the caller).
template <class F>
void with_stage_messages(const std::string& type, F&& f) {
  try {
    f();
  } catch (const Error& e) {
    py::gil_scoped_acquire gil;
    ErrorPlace place = e.place();
    place.origin.clear();
    place.stage_index = 0;
    if (!place.stage.empty()) place.stage = type;
    raise_python(e, place, place.stage.empty() ? e.message() : type + ": " + e.message());
  }
}

/// Runs stage `name` over `inputs` (PointCloud / TriangleMesh objects, one per consumed slot, or
/// any number for a list slot) with `params` as (key, text) pairs. Returns (product or None,
/// report JSON text).
py::tuple run_stage(const std::string& name, const py::list& inputs, const std::vector<std::pair<std::string, std::string>>& params,
                    const py::object& progress) {
  const StageSpec* spec = find_stage(name);
  if (spec == nullptr) throw UsageError(fmt::format("unknown stage \"{}\"", name));
  const std::string origin = "pointsurf." + name;
  std::vector<StepText> steps;
  std::vector<std::string> tags;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    tags.push_back(fmt::format("input{}", i + 1));
    steps.push_back(StepText{"read", tags.back(), {}, {{"filename", "input.ply"}}});
  }
  steps.push_back(StepText{name, "output", tags, params});
  const bool ends = spec->shape == CommandShape::Write || spec->measures() || !spec->writes_param.empty();
  if (!ends) steps.push_back(StepText{"write", "", {"output"}, {{"filename", "output.ply"}}});
  const std::size_t index = inputs.size();

  Pipeline pipeline;
  with_stage_messages(name, [&] {
    Pipeline built = build_pipeline(steps, origin);
    pipeline.origin = origin;
    pipeline.steps.push_back(std::move(built.steps[index]));
  });
  auto context = std::make_shared<Context>();
  for (std::size_t i = 0; i < inputs.size(); ++i) context->set(tags[i], to_item(inputs[i]));

  RunReport report;
  report.command = name;
  Watch watch(progress);
  RunOptions options;
  options.progress = [&](const StageRecord&) { return watch.hook(); };
  with_stage_messages(name, [&] { watch.run([&] { run_pipeline(pipeline, *context, report, options); }); });
  py::object product = py::none();
  if (spec->produces && context->has("output")) product = from_item(std::move(context->item("output")));
  return py::make_tuple(product, report_json(report));
}

/// Runs a whole JSON pipeline (the CLI's `run`); returns the report JSON text.
std::string run_json(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides,
                     const py::object& progress) {
  const Pipeline pipeline = parse_pipeline(text, origin, overrides);
  Context context;
  RunReport report;
  report.command = "run";
  Watch watch(progress);
  RunOptions options;
  options.progress = [&](const StageRecord&) { return watch.hook(); };
  watch.run([&] { run_pipeline(pipeline, context, report, options); });
  return report_json(report);
}

}  // namespace

void bind_stages(py::module_& m) {
  // Python's classes for the library's errors, one per kind; an error raised elsewhere (a whole
  // pipeline, a reader) keeps the pipeline's wording, Error::what().
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<UsageError> usage(m, "UsageError", error.ptr());
  static py::exception<InputError> input(m, "InputError", error.ptr());
  static py::exception<ComputeError> compute(m, "ComputeError", error.ptr());
  static py::exception<CancelledError> cancelled(m, "CancelledError", compute.ptr());
  error_classes = {usage.ptr(), input.ptr(), compute.ptr(), cancelled.ptr()};
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      try {
        raise_python(e, e.place(), e.what());
      } catch (py::error_already_set& raised) {
        raised.restore();
      }
    }
  });
  m.def("stages", &stage_list, "Every registered stage with its parameters, as plain data.");
  m.def("run_stage", &run_stage, py::arg("name"), py::arg("inputs"), py::arg("params"), py::arg("progress") = py::none());
  m.def("run_json", &run_json, py::arg("text"), py::arg("origin"), py::arg("overrides") = std::vector<std::string>{},
        py::arg("progress") = py::none());
}

}  // namespace pointsurf::python
