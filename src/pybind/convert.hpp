#pragma once
// Values between C++ and Python for the module's files.

#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/core/geometry.hpp"

namespace overtake::pybind {

// A JSON value (a report) as Python values.
inline pybind11::object to_python(const nlohmann::json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::boolean:
      return pybind11::bool_(j.get<bool>());
    case T::number_integer:
      return pybind11::int_(j.get<std::int64_t>());
    case T::number_unsigned:
      return pybind11::int_(j.get<std::uint64_t>());
    case T::number_float:
      return pybind11::float_(j.get<double>());
    case T::string:
      return pybind11::str(j.get_ref<const std::string&>());
    case T::array: {
      pybind11::list l;
      for (const auto& e : j) l.append(to_python(e));
      return l;
    }
    case T::object: {
      pybind11::dict d;
      for (const auto& [k, v] : j.items()) d[pybind11::str(k)] = to_python(v);
      return d;
    }
    default:
      return pybind11::none();
  }
}

/// A path as a planner answers it to Python: (path_x, path_y), two lists.
inline pybind11::tuple path_to_python(const std::vector<core::Vec2>& path) {
  pybind11::list xs(path.size());
  pybind11::list ys(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    xs[i] = path[i].x;
    ys[i] = path[i].y;
  }
  return pybind11::make_tuple(xs, ys);
}

}  // namespace overtake::pybind
