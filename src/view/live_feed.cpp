// The live feed of a run: the records a run publishes as it goes (LiveRecorder, on the run's
// thread) and the chunks a viewer's connection reads (LiveFeed::next, on the server's thread).

#include <chrono>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <utility>

#include "overtake/view/server.hpp"

namespace overtake::view {
namespace {

constexpr long kPublishEverySteps = 5;  // 0.1 s at the original's 50 Hz

}  // namespace

LiveFeed::LiveFeed(std::string header_json) : header_json_(std::move(header_json)) {}

void LiveFeed::publish(std::string records) {
  if (records.empty()) return;
  auto chunk = std::make_shared<const std::string>(std::move(records));
  const std::lock_guard lock(mu_);
  chunks_.push_back(std::move(chunk));
}

void LiveFeed::close() {
  const std::lock_guard lock(mu_);
  closed_ = true;
}

LiveFeed::Next LiveFeed::next(std::size_t from) const {
  const std::lock_guard lock(mu_);
  Next out;
  if (from < chunks_.size())
    out.chunks.assign(chunks_.begin() + static_cast<long>(from), chunks_.end());
  out.closed = closed_;
  return out;
}

LiveRecorder::LiveRecorder(LiveFeed& feed) : feed_(feed) {}

void LiveRecorder::on_frame(const sim::Frame& frame, std::span<const sim::Incident> new_incidents) {
  if (!first_step_) {
    first_step_ = frame.step;
    last_publish_step_ = frame.step;
  }
  encoder_.append_frame(frame, pending_);
  encoder_.append_incidents(new_incidents, pending_);
  if (frame.step == *first_step_ || frame.step - last_publish_step_ >= kPublishEverySteps) {
    publish();
    last_publish_step_ = frame.step;
  }
}

void LiveRecorder::on_path(std::span<const core::Vec2> path) {
  encoder_.append_path(path, pending_);
}

void LiveRecorder::finish(std::string_view report_json) {
  replay::ReplayEncoder::append_end(report_json, pending_);
  publish();
  feed_.close();
}

void LiveRecorder::publish() {
  feed_.publish(std::move(pending_));
  pending_.clear();
}

}  // namespace overtake::view
