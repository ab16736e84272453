#pragma once
// Small file helpers for the command line.

#include <filesystem>
#include <string>
#include <string_view>

namespace overtake::app {

/// The whole file; throws std::runtime_error naming the path when it cannot be read.
[[nodiscard]] std::string read_file(const std::filesystem::path& path);

/// Writes through a temporary file and a rename, so that a reader never sees half a file
/// and a failure leaves any previous file in place. Throws std::runtime_error naming the path.
/// A path that is not a regular file (/dev/null, /dev/stdout, a pipe) is written in place.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace overtake::app
