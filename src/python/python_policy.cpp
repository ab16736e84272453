#include "overtake/python/python_policy.hpp"

namespace overtake::python {

LoadedPython load_python_policy(const std::string& spec) {
  throw PythonError(spec + ": Python planners are not built yet");
}

}  // namespace overtake::python
