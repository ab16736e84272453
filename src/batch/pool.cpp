#include "overtake/batch/pool.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "overtake/base/errors.hpp"

namespace overtake::batch {

int default_jobs() {
  return static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
}
namespace {

// What the threads share with the calling thread; every field but the atomics under `mu`.
struct PoolState {
  std::mutex mu;
  std::condition_variable cv;
  std::set<std::size_t> finished;                    // done, not yet taken
  std::map<std::size_t, std::exception_ptr> failed;  // thrown, not yet rethrown
  int running = 0;                                   // threads not yet ended
  std::atomic<std::size_t> next{0};                  // the next item to start
  std::atomic<bool> halt{false};
};

// Whose turn it is, under the lock: an item finished or failed, or none yet.
struct Turn {
  std::optional<std::size_t> item;
  std::exception_ptr error;
};

Turn next_turn(PoolState& s, PoolOrder order, std::size_t next_in_order) {
  Turn t;
  if (order == PoolOrder::by_index) {
    if (s.finished.erase(next_in_order) > 0) {
      t.item = next_in_order;
    } else if (const auto it = s.failed.find(next_in_order); it != s.failed.end()) {
      t.error = it->second;
    }
    return t;
  }
  // As finished, lowest index first: an error is rethrown at once.
  if (!s.failed.empty()) {
    t.error = s.failed.begin()->second;
  } else if (!s.finished.empty()) {
    t.item = *s.finished.begin();
    s.finished.erase(s.finished.begin());
  }
  return t;
}

void work_loop(PoolState& s, std::size_t count, const std::atomic<bool>* stop,
               const std::function<void(std::size_t, const std::atomic<bool>*)>& work) {
  for (;;) {
    if (s.halt.load() || (stop != nullptr && stop->load())) break;
    const std::size_t i = s.next.fetch_add(1);
    if (i >= count) break;
    std::exception_ptr error;
    try {
      work(i, &s.halt);
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard lock(s.mu);
    if (error) {
      s.failed.emplace(i, error);
    } else {
      s.finished.insert(i);
    }
    s.cv.notify_all();
  }
  const std::lock_guard lock(s.mu);
  --s.running;
  s.cv.notify_all();
}

}  // namespace

void check_jobs(int jobs) {
  if (jobs < 1 || jobs > kMaxJobs) {
    throw base::UsageError("--jobs must be between 1 and " + std::to_string(kMaxJobs) + " (got " +
                           std::to_string(jobs) + ")");
  }
}

PoolEnd run_pool_indices(std::size_t count, const PoolOptions& options,
                         const std::function<void(std::size_t, const std::atomic<bool>*)>& work,
                         const std::function<bool(std::size_t)>& take) {
  check_jobs(options.jobs);
  PoolState s;
  const auto threads = static_cast<int>(std::min<std::size_t>(
      static_cast<std::size_t>(options.jobs), std::max<std::size_t>(count, 1)));
  s.running = threads;
  std::vector<std::thread> pool;
  // However the pool ends (its end, the consumer, an exception), its threads are halted and
  // joined before it returns or throws.
  struct Joiner {
    PoolState& s;
    std::vector<std::thread>& pool;
    ~Joiner() {
      s.halt = true;
      for (std::thread& t : pool) t.join();
    }
  } joiner{s, pool};
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&] { work_loop(s, count, options.stop, work); });
  }
  PoolEnd end;
  const auto tick = std::chrono::duration<double>(kPoolTickS);
  auto last_tick = std::chrono::steady_clock::now();
  for (;;) {
    Turn turn;
    bool all_done = false;
    {
      std::unique_lock lock(s.mu);
      s.cv.wait_for(lock, tick, [&] {
        if (s.running == 0) return true;
        if (options.order == PoolOrder::as_finished) {
          return !s.finished.empty() || !s.failed.empty();
        }
        return s.finished.count(end.delivered) > 0 || s.failed.count(end.delivered) > 0;
      });
      turn = next_turn(s, options.order, end.delivered);
      all_done = s.running == 0 && !turn.item && !turn.error;
    }
    if (options.stop != nullptr && options.stop->load()) {
      s.halt = true;
      end.stopped = true;
    }
    if (turn.error) std::rethrow_exception(turn.error);
    if (turn.item) {
      ++end.delivered;
      if (!take(*turn.item)) {
        end.ended_by_consumer = true;
        break;
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (options.tick && (now - last_tick >= tick || all_done)) {
      last_tick = now;
      options.tick();
    }
    if (all_done) break;
  }
  return end;
}

}  // namespace overtake::batch
