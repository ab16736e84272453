#include "step_pool.hpp"

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

// Share `share` of count_ items among workers_.size() + 1 threads: contiguous, the first ones
// one item longer when they do not divide.
void StepPool::run_share(std::size_t share) {
  const std::size_t shares = workers_.size() + 1;
  const std::size_t base = count_ / shares;
  const std::size_t extra = count_ % shares;
  const std::size_t begin = share * base + std::min(share, extra);
  const std::size_t end = begin + base + (share < extra ? 1 : 0);
  try {
    for (std::size_t i = begin; i < end; ++i) (*work_)(i);
  } catch (...) {
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
    run_share(worker);
    {
      const std::lock_guard lock(mu_);
      --busy_;
    }
    done_.notify_one();
  }
}

void StepPool::run(std::size_t count, const std::function<void(std::size_t)>& work) {
  {
    const std::lock_guard lock(mu_);
    count_ = count;
    work_ = &work;
    error_ = nullptr;
    busy_ = workers_.size();
    ++generation_;
  }
  wake_.notify_all();
  run_share(0);
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
