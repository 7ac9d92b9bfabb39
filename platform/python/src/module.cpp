// _beslam: the C++ half of the Python package `beslam` (platform/python/beslam/__init__.py is the other).
// Exposes the host's own trajectory readers and evaluator, so Python reads a run's files and scores them
// exactly as `beslam eval` does: read_trajectory(path, format) -> (stamps (N,), poses (N, 4, 4)),
// evaluate(ref, est, ...) -> the JSON text `beslam eval --json` writes, detect_format(path) -> "kitti" | "tum". Errors
// arrive as ValueError with the host's one-line message (naming the file). No plugin is loaded and no pipeline is run
// here.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "beslam/eval/eval.hpp"
#include "beslam/formats/error.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace py = pybind11;

namespace {

py::tuple readTrajectory(const std::string& path, const std::string& format) {
  beslam::trajectory::Trajectory t;
  try {
    t = beslam::trajectory::read(path, format.empty() ? beslam::trajectory::detectFormat(path) : format);
  } catch (const beslam::Error& e) {
    throw py::value_error(e.what());
  }
  const py::ssize_t n = static_cast<py::ssize_t>(t.size());
  py::array_t<double> stamps(n), poses({n, py::ssize_t{4}, py::ssize_t{4}});
  auto s = stamps.mutable_unchecked<1>();
  auto p = poses.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < n; ++i) {
    s(i) = t.stamps[static_cast<size_t>(i)];
    const Eigen::Matrix4d& m = t.poses[static_cast<size_t>(i)].matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) p(i, r, c) = m(r, c);
  }
  return py::make_tuple(stamps, poses);
}

std::string evaluate(const std::string& ref, const std::string& est, const std::string& format,
                     const std::string& align, size_t align_first, double max_diff, double offset, size_t delta,
                     bool all_pairs) {
  if (!format.empty() && format != "kitti" && format != "tum")
    throw py::value_error("format must be kitti, tum or '' (detected from the reference), not '" + format + "'");
  beslam::eval::EvalOptions options;
  options.format = format;
  options.align_first_n = align_first;
  options.max_diff = max_diff;
  options.est_time_offset = offset;
  options.delta = delta;
  options.all_pairs = all_pairs;
  if (align != "none" && align != "se3" && align != "sim3")
    throw py::value_error("align must be none, se3 or sim3, not '" + align + "'");
  try {
    options.alignment = beslam::eval::parseAlignmentType(align);
    std::string problem;
    if (!options.isValid(&problem)) throw py::value_error(problem);
    return beslam::eval::toJson(beslam::eval::evaluateFiles(ref, est, options));
  } catch (const beslam::Error& e) {
    throw py::value_error(e.what());
  }
}

}  // namespace

std::string detectFormat(const std::string& path) {
  try {
    return beslam::trajectory::detectFormat(path);
  } catch (const beslam::Error& e) {
    throw py::value_error(e.what());
  }
}

PYBIND11_MODULE(_beslam, m) {
  m.doc() = "BE-SLAM's trajectory readers and evaluator (the C++ half of the beslam package)";
  m.def("read_trajectory", &readTrajectory, py::arg("path"), py::arg("format") = "",
        "(stamps, poses): a KITTI or TUM trajectory file (format '' detects it) as arrays of shape (N,) and "
        "(N, 4, 4), T_world_cam; raises ValueError naming the file on bad input");
  m.def("detect_format", &detectFormat, py::arg("path"),
        "'kitti' or 'tum', from the column count of the file's first data row (as beslam eval detects it)");
  m.def("evaluate", &evaluate, py::arg("ref"), py::arg("est"), py::arg("format") = "", py::arg("align") = "none",
        py::arg("align_first") = 0, py::arg("max_diff") = 0.01, py::arg("offset") = 0.0, py::arg("delta") = 1,
        py::arg("all_pairs") = false, "`beslam eval --json`'s text for two trajectory files");
}
