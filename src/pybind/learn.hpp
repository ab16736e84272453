#pragma once
// The learning environment's part of the Python module (learn.cpp).

#include <pybind11/pybind11.h>

namespace overtake::pybind {

/// Registers VecEnvCore and the observation's layout constants on the module.
void register_learning(pybind11::module_& m);

}  // namespace overtake::pybind
