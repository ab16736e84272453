#pragma once
// Files as every room reads and writes them: bounded reads, atomic writes, and whether two
// paths name one file.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace overtake::base {

/// What read_file reads at most unless told otherwise: far more than any text file overtake
/// reads (its largest, a bench's runs.jsonl of 10,000 runs, is about 20 MB).
inline constexpr std::uintmax_t kMaxReadBytes = 256ULL << 20;

/// The whole file; throws std::runtime_error naming the path when it cannot be read, when it
/// is not a regular file (a device such as /dev/zero, a FIFO, a directory: opened without
/// waiting for a writer, and never read) or when it holds more than max_bytes.
[[nodiscard]] std::string read_file(const std::filesystem::path& path,
                                    std::uintmax_t max_bytes = kMaxReadBytes);

/// Writes through a temporary file and a rename, so that a reader never sees half a file
/// and a failure leaves any previous file in place. Throws std::runtime_error naming the path.
/// A path that is not a regular file (/dev/null, /dev/stdout, a pipe) is written in place.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// True when `a` and `b` name the same file (after resolving . and .., symbolic links of
/// existing parts, and hard links of existing files).
[[nodiscard]] bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// Standard output's reader has gone (EPIPE: `overtake config | head`). Not an error to
/// report: the reader stopped reading on purpose; the command line exits without a message.
class OutputClosed : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Flushes standard output and throws std::runtime_error when anything written to it was lost
/// (a full disk, an error of the device): a command whose output did not arrive must not exit
/// 0. Throws OutputClosed when the reader of a pipe has gone.
void flush_stdout_or_throw();

/// Whether progress lines may be drawn (stderr is a terminal).
[[nodiscard]] bool stderr_is_terminal();

/// One status line on stderr, drawn over each time (a long command's progress): silent unless
/// enabled and stderr is a terminal; ends its line when destroyed, however the command ends.
class StatusLine {
 public:
  explicit StatusLine(bool enabled) : on_(enabled && stderr_is_terminal()) {}
  ~StatusLine();
  StatusLine(const StatusLine&) = delete;
  StatusLine& operator=(const StatusLine&) = delete;

  /// Draws `text` over the line (when on).
  void draw(std::string_view text);
  [[nodiscard]] bool on() const { return on_; }

 private:
  bool on_;
  bool drawn_ = false;
};

}  // namespace overtake::base
