// `--policy-py` in a build without Python (OVERTAKE_PYTHON=OFF).
#include "overtake/python/python_policy.hpp"

namespace overtake::python {

LoadedPython load_python_policy(const std::string& spec) {
  throw PythonError(spec + ": this build has no Python (configure with OVERTAKE_PYTHON=ON)");
}

}  // namespace overtake::python
