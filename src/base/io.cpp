#include "overtake/base/io.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <system_error>

namespace overtake::base {

namespace {

std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string megabytes(std::uintmax_t bytes) {
  const std::uintmax_t mib = bytes >> 20;
  return mib > 0 ? std::to_string(mib) + " MiB" : std::to_string(bytes) + " bytes";
}

}  // namespace

std::string read_file(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  // O_NONBLOCK: a FIFO opens at once instead of waiting for a writer (and is then refused).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    throw std::runtime_error(path.string() + ": cannot read (" + std::strerror(errno) + ")");
  }
  if (!S_ISREG(st.st_mode)) {
    throw std::runtime_error(path.string() + ": is " + kind_of(st.st_mode) +
                             ", not a regular file");
  }
  const auto too_big = [&] {
    return std::runtime_error(path.string() + ": larger than the " + megabytes(max_bytes) +
                              " this reads");
  };
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) throw too_big();
  std::string out;
  out.reserve(static_cast<std::size_t>(st.st_size));
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(path.string() + ": read error (" + std::strerror(errno) + ")");
    }
    out.append(chunk, static_cast<std::size_t>(n));
    if (out.size() > max_bytes) throw too_big();  // it grew while read
  }
  return out;
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  // A device, a pipe or a terminal (/dev/null, /dev/stdout, ...) is written in place: a
  // rename would replace it with a regular file.
  std::error_code status_ec;
  const auto status = std::filesystem::status(path, status_ec);
  if (!status_ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    std::ofstream out(path, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) throw std::runtime_error(path.string() + ": write failed");
    return;
  }
  const std::filesystem::path tmp =
      path.string() + ".tmp." + std::to_string(static_cast<long>(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw std::runtime_error(path.string() + ": cannot write (" + std::strerror(errno) + ")");
    }
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(path.string() + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path.string() + ": cannot replace (" + ec.message() + ")");
  }
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) {
    const bool eq = std::filesystem::equivalent(a, b, ec);
    if (!ec) return eq;
  }
  const auto ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a), ec);
  const auto cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b), ec);
  return !ec && ca == cb;
}

bool stderr_is_terminal() {
  return ::isatty(STDERR_FILENO) != 0;
}

namespace {

// Whether `fd` is a pipe whose reading end is closed (the write error itself may have come
// while stdio flushed earlier, its errno long overwritten).
bool reader_gone(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISFIFO(st.st_mode)) return false;
  pollfd p{fd, POLLOUT, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & POLLERR) != 0;
}

}  // namespace

void flush_stdout_or_throw() {
  errno = 0;
  std::cout.flush();
  int err = errno;
  const bool lost = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  if (err == 0) err = errno;
  if (lost) {
    std::cout.clear();
    std::clearerr(stdout);
    if (err == EPIPE || reader_gone(STDOUT_FILENO)) {
      throw OutputClosed("standard output: the reader has gone");
    }
    throw std::runtime_error(std::string("standard output: write failed") +
                             (err ? std::string(" (") + std::strerror(err) + ")" : std::string()) +
                             "; the output is incomplete");
  }
}

StatusLine::~StatusLine() {
  if (drawn_) std::fputc('\n', stderr);
}

void StatusLine::draw(std::string_view text) {
  if (!on_) return;
  std::fprintf(stderr, "\r%.*s", static_cast<int>(text.size()), text.data());
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace overtake::base
