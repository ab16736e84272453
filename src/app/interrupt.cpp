#include "overtake/app/interrupt.hpp"

namespace overtake::app {
namespace {

extern "C" void on_interrupt(int) {
  InterruptScope::flag().store(true);
}

}  // namespace

std::atomic<bool>& InterruptScope::flag() {
  static std::atomic<bool> interrupted{false};
  return interrupted;
}

InterruptScope::InterruptScope() {
  flag().store(false);
  old_int_ = std::signal(SIGINT, on_interrupt);
  old_term_ = std::signal(SIGTERM, on_interrupt);
}

InterruptScope::~InterruptScope() {
  std::signal(SIGINT, old_int_);
  std::signal(SIGTERM, old_term_);
}

}  // namespace overtake::app
