#include "overtake/learn/step_pool.hpp"

#include <algorithm>

namespace overtake::learn {

StepPool::StepPool(int threads) {
  const auto n = static_cast<std::size_t>(std::max(1, threads));
  for (std::size_t w = 1; w < n; ++w) workers_.emplace_back([this, w] { serve(w); });
}

StepPool::~StepPool() {
  {
    const std::lock_guard lock(mu_);
    quit_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void StepPool::take_items(std::size_t worker) {
  try {
    for (;;) {
      if (failed_.load(std::memory_order_relaxed)) return;
      const std::size_t i = next_.fetch_add(1, std::memory_order_relaxed);
      if (i >= count_) return;
      (*work_)(i, worker);
    }
  } catch (...) {
    failed_.store(true, std::memory_order_relaxed);
    const std::lock_guard lock(mu_);
    if (!error_) error_ = std::current_exception();
  }
}

void StepPool::serve(std::size_t worker) {
  long seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mu_);
      wake_.wait(lock, [&] { return quit_ || generation_ != seen; });
      if (quit_) return;
      seen = generation_;
    }
    take_items(worker);
    {
      const std::lock_guard lock(mu_);
      --busy_;
    }
    done_.notify_one();
  }
}

void StepPool::run(std::size_t count, const std::function<void(std::size_t, std::size_t)>& work) {
  {
    const std::lock_guard lock(mu_);
    count_ = count;
    work_ = &work;
    error_ = nullptr;
    next_.store(0, std::memory_order_relaxed);
    failed_.store(false, std::memory_order_relaxed);
    busy_ = workers_.size();
    ++generation_;
  }
  wake_.notify_all();
  take_items(0);
  std::exception_ptr error;
  {
    std::unique_lock lock(mu_);
    done_.wait(lock, [&] { return busy_ == 0; });
    error = error_;
    work_ = nullptr;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace overtake::learn
