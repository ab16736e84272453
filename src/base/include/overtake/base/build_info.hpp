#pragma once
// What this binary was built from: the project's version and the git revision of the source
// tree, both written at build time (cmake/write_build_info.cmake), so that a rebuild after a
// new commit reports the new revision.

#include <string>
#include <string_view>

namespace overtake::base {

/// The project's version (the top-level CMakeLists.txt), e.g. "0.1.0".
[[nodiscard]] std::string_view project_version();

/// `git rev-parse --short=12 HEAD` of the source tree at the last build, or "unknown" when the
/// binary was built outside a git checkout.
[[nodiscard]] std::string_view build_revision();

/// This build's version, e.g. "0.1.0+c0733af12345" (the git revision it was built from).
[[nodiscard]] inline std::string overtake_version() {
  return std::string(project_version()) + "+" + std::string(build_revision());
}

}  // namespace overtake::base
