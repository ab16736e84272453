#pragma once
// The environment's threads (learn/vec_env.cpp): kept for its lifetime, woken for each call,
// the calling thread among them. Each takes the next env not yet taken until none is left, so
// that a thread whose worlds plan quickly takes more of them and none waits on a slow share. A
// call of a few milliseconds costs no thread's start.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace overtake::learn {

class StepPool {
 public:
  /// `threads` in all, the caller's among them (at least 1).
  explicit StepPool(int threads);
  ~StepPool();
  StepPool(const StepPool&) = delete;
  StepPool& operator=(const StepPool&) = delete;

  /// The threads in all, the caller's among them: `worker` of run()'s work is below this.
  [[nodiscard]] std::size_t threads() const { return workers_.size() + 1; }

  /// work(i, worker) for every i in [0, count), shared among the threads (`worker`: which
  /// thread, 0 the caller's; no two run at once with the same one); returns when all are
  /// done, rethrowing the first exception one of them threw. After an exception no thread
  /// takes another item; those already taken finish.
  void run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& work);

 private:
  void serve(std::size_t worker);
  void take_items(std::size_t worker);

  std::vector<std::thread> workers_;
  std::mutex mu_;
  std::condition_variable wake_;
  std::condition_variable done_;
  long generation_ = 0;
  std::size_t busy_ = 0;
  bool quit_ = false;
  std::size_t count_ = 0;
  std::atomic<std::size_t> next_{0};  // the next item not yet taken
  std::atomic<bool> failed_{false};
  const std::function<void(std::size_t, std::size_t)>* work_ = nullptr;
  std::exception_ptr error_;
};

}  // namespace overtake::learn
