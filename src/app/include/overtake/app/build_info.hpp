#pragma once
// What this binary was built from: the project's version and the git revision of the source
// tree, both written at build time (cmake/write_build_info.cmake), so that a rebuild after a
// new commit reports the new revision.

#include <string_view>

namespace overtake::app {

/// The project's version (the top-level CMakeLists.txt), e.g. "0.1.0".
[[nodiscard]] std::string_view project_version();

/// `git rev-parse --short=12 HEAD` of the source tree at the last build, or "unknown" when the
/// binary was built outside a git checkout.
[[nodiscard]] std::string_view build_revision();

}  // namespace overtake::app
