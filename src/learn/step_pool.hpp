#pragma once
// The environment's threads (learn/vec_env.cpp): kept for its lifetime, woken for each call,
// each taking a contiguous share of the envs; the calling thread takes the first share. A call
// of a few milliseconds costs no thread's start.

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

  /// work(i) for every i in [0, count), shared among the threads; returns when all are done,
  /// rethrowing the first exception one of them threw (the others' items still ran).
  void run(std::size_t count, const std::function<void(std::size_t)>& work);

 private:
  void serve(std::size_t worker);
  void run_share(std::size_t share);

  std::vector<std::thread> workers_;
  std::mutex mu_;
  std::condition_variable wake_;
  std::condition_variable done_;
  long generation_ = 0;
  std::size_t busy_ = 0;
  bool quit_ = false;
  std::size_t count_ = 0;
  const std::function<void(std::size_t)>* work_ = nullptr;
  std::exception_ptr error_;
};

}  // namespace overtake::learn
