// Reports handed to Python: typed attributes per report kind over a common base whose
// to_dict() is the library's JSON (the same keys as the command line's --report files).
#pragma once
#include <string>

#include "common.hpp"
#include "vpm/json.hpp"

namespace vpm::python {

struct Report {
  virtual ~Report() = default;
  std::string json;  ///< the library's to_json(...) of the result, compact
};

/// The library's JSON as Python objects (dicts, lists, numbers, strings).
inline py::object json_to_python(const Json& j) { return py::module_::import("json").attr("loads")(j.dump(-1)); }

/// vpm.Report: to_dict() and __repr__ (bound once, in bind_map).
inline void bind_report_base(py::module_& m) {
  py::class_<Report>(m, "Report", "Base of vpm's reports: to_dict() gives the report's JSON as a dict.")
      .def("to_dict", [](const Report& r) { return py::module_::import("json").attr("loads")(r.json); },
           "The whole report as a dict (the keys of the command line's --report JSON).")
      .def("__repr__", [](const py::object& self) {
        return "<vpm." + self.attr("__class__").attr("__name__").cast<std::string>() + ">";
      });
}

}  // namespace vpm::python
