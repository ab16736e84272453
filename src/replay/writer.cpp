// The streaming writer: records deflated (zlib) into FILE.partial as the run goes, renamed
// to FILE when finished.

#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "wire.hpp"

namespace overtake::replay {
namespace {

/// How many FILE[.n].partial names a recording tries before giving up.
constexpr int kMaxPartialNames = 1000;

}  // namespace

using namespace wire;

struct ReplayWriter::Impl {
  std::filesystem::path final_path;
  std::filesystem::path partial_path;
  std::FILE* file = nullptr;
  z_stream z{};
  bool z_open = false;
  ReplayEncoder encoder;
  std::string pending;  // records not yet deflated
  std::vector<unsigned char> out_buf = std::vector<unsigned char>(kDeflateChunkBytes);
  std::size_t since_sync = 0;  // record bytes deflated since the last sync flush
  std::uint64_t written = 0;
  std::string error;  // the first failure; nothing more is written after it
  bool finished = false;
  bool exact_paths = false;  // paths also as sent, bit for bit
  bool in_place = false;     // a device or pipe: written directly, never renamed
  sim::CheckpointInfo checkpoint_info;

  void fail(const std::string& what) {
    if (error.empty()) error = partial_path.string() + ": " + what;
  }

  void write(const void* data, std::size_t n) {
    if (!error.empty() || n == 0) return;
    if (std::fwrite(data, 1, n, file) != n) {
      fail(std::string("cannot write (") + std::strerror(errno) + ")");
      return;
    }
    written += n;
  }

  // Deflates `pending` with `flush` (Z_NO_FLUSH, Z_SYNC_FLUSH or Z_FINISH) and writes out.
  void deflate_pending(int flush) {
    if (!error.empty()) return;
    z.next_in = reinterpret_cast<Bytef*>(pending.data());
    z.avail_in = static_cast<uInt>(pending.size());
    since_sync += pending.size();
    for (;;) {
      z.next_out = out_buf.data();
      z.avail_out = static_cast<uInt>(out_buf.size());
      const int rc = deflate(&z, flush);
      if (rc == Z_STREAM_ERROR) {
        fail("compression failed (zlib stream error)");
        return;
      }
      write(out_buf.data(), out_buf.size() - z.avail_out);
      if (!error.empty()) return;
      if (flush == Z_FINISH ? rc == Z_STREAM_END : (z.avail_in == 0 && z.avail_out != 0)) break;
    }
    pending.clear();
    if (flush != Z_NO_FLUSH) since_sync = 0;
  }

  void maybe_deflate() {
    if (pending.size() < kDeflateChunkBytes) return;
    deflate_pending(since_sync + pending.size() >= kSyncEveryBytes ? Z_SYNC_FLUSH : Z_NO_FLUSH);
    if (error.empty() && since_sync == 0 && std::fflush(file) != 0) {
      fail(std::string("cannot write (") + std::strerror(errno) + ")");
    }
  }

  void close_all() {
    if (z_open) {
      deflateEnd(&z);
      z_open = false;
    }
    if (file) {
      if (std::fclose(file) != 0) fail(std::string("cannot write (") + std::strerror(errno) + ")");
      file = nullptr;
    }
  }

  void complete(std::string_view report_json) {
    finished = true;
    ReplayEncoder::append_end(report_json, pending);
    deflate_pending(Z_FINISH);
    close_all();
    if (!error.empty() || in_place) return;
    std::error_code ec;
    std::filesystem::rename(partial_path, final_path, ec);
    if (ec) {
      error = final_path.string() + ": cannot rename " + partial_path.string() + " to it (" +
              ec.message() + ")";
    }
  }
};

ReplayWriter::ReplayWriter(const std::filesystem::path& path, const ReplayHeader& header)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.final_path = path;
  m.partial_path = path;
  // A device or a pipe (/dev/null, /dev/stdout) is written in place: a rename would replace
  // it with a regular file.
  std::error_code status_ec;
  const auto status = std::filesystem::status(path, status_ec);
  m.in_place =
      !status_ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status);
  if (m.in_place) {
    m.file = std::fopen(m.partial_path.c_str(), "wb");
  } else {
    // FILE.partial, created exclusively: a second recording to the same file at the same time,
    // or an earlier killed run's FILE.partial (kept for `view --partial`), takes the next free
    // name FILE.1.partial, FILE.2.partial, ...; each run renames its own file to FILE when done,
    // so FILE always holds a whole replay.
    for (int n = 0; n < kMaxPartialNames && !m.file; ++n) {
      m.partial_path = path;
      m.partial_path += n == 0 ? std::string(".partial") : "." + std::to_string(n) + ".partial";
      m.file = std::fopen(m.partial_path.c_str(), "wbx");
      if (!m.file && errno != EEXIST) break;
    }
  }
  if (!m.file) {
    throw ReplayError(m.partial_path.string() + ": cannot create the replay file (" +
                      std::strerror(errno) + ")");
  }
  if (deflateInit(&m.z, kDeflateLevel) != Z_OK) {
    std::fclose(m.file);
    m.file = nullptr;
    throw ReplayError(m.partial_path.string() + ": cannot start the compressor (zlib)");
  }
  m.z_open = true;
  const std::string preamble = replay_preamble(header);
  m.write(preamble.data(), preamble.size());
  if (!m.error.empty()) {
    const std::string why = m.error;
    m.close_all();
    throw ReplayError(why);
  }
}

ReplayWriter::~ReplayWriter() {
  if (!impl_ || impl_->finished) return;
  try {
    impl_->complete(kUnfinishedReport);
  } catch (...) {  // a destructor does not throw; the partial file stays
  }
  impl_->close_all();
}

void ReplayWriter::on_frame(const sim::Frame& frame, std::span<const sim::Incident> new_incidents) {
  Impl& m = *impl_;
  if (m.finished || !m.error.empty()) return;
  m.encoder.append_frame(frame, m.pending);
  m.encoder.append_incidents(new_incidents, m.pending);
  m.maybe_deflate();
}

void ReplayWriter::on_path(std::span<const core::Vec2> path) {
  Impl& m = *impl_;
  if (m.finished || !m.error.empty()) return;
  m.encoder.append_path(path, m.pending, m.exact_paths);
  m.maybe_deflate();
}

void ReplayWriter::set_exact_paths(bool exact) {
  impl_->exact_paths = exact;
}

void ReplayWriter::set_checkpoint_info(sim::CheckpointInfo info) {
  impl_->checkpoint_info = std::move(info);
}

void ReplayWriter::on_checkpoint(const sim::Checkpoint& checkpoint) {
  Impl& m = *impl_;
  if (m.finished || !m.error.empty()) return;
  sim::Checkpoint c = checkpoint;
  const long step = c.info.step;
  const double t = c.info.t_s;
  c.info = m.checkpoint_info;
  c.info.step = step;
  c.info.t_s = t;
  ReplayEncoder::append_checkpoint(sim::encode_checkpoint(c), m.pending);
  m.maybe_deflate();
}

void ReplayWriter::finish(std::string_view report_json) {
  Impl& m = *impl_;
  if (m.finished) throw ReplayError(m.final_path.string() + ": the replay was already finished");
  m.complete(report_json);
  if (!m.error.empty()) throw ReplayError(m.error);
}

std::uint64_t ReplayWriter::bytes_written() const {
  return impl_->written;
}

const std::filesystem::path& ReplayWriter::partial_path() const {
  return impl_->finished && impl_->error.empty() ? impl_->final_path : impl_->partial_path;
}

}  // namespace overtake::replay
