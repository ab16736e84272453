#pragma once
// The one worker pool of the batch room: a bench's runs, a hunt's, a suite's scenario runs,
// calibration's seeds and the bench's re-runs with a replay are items 0..count-1 of a list,
// taken in index order by up to `jobs` threads; their results are handed, on the calling
// thread, to one consumer (as each finishes, or in index order), which needs no lock.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <utility>

namespace overtake::batch {

/// The most threads one pool runs (--jobs): past it, threads only wait on each other.
inline constexpr int kMaxJobs = 256;

/// The --jobs a command takes when not told: one per hardware thread (at least one).
[[nodiscard]] int default_jobs();
/// How often, while results are awaited, the pool looks at the stop flag and calls its tick.
inline constexpr double kPoolTickS = 0.1;

/// Throws UsageError "--jobs must be between 1 and kMaxJobs (got N)".
void check_jobs(int jobs);

/// In which order results reach the consumer.
enum class PoolOrder : std::uint8_t {
  as_finished,  ///< each as soon as it is done (lowest index first among those waiting)
  by_index,     ///< in index order: what the consumer sees does not depend on `jobs`
};

/// How a pool runs.
struct PoolOptions {
  int jobs = 1;  ///< threads, 1 to kMaxJobs (fewer when there are fewer items)
  /// Polled (may be null): once set, no item starts; items in progress see the pool's halt
  /// flag set within kPoolTickS, and the results that come are still delivered.
  const std::atomic<bool>* stop = nullptr;
  PoolOrder order = PoolOrder::as_finished;
  /// Called on the calling thread about every kPoolTickS while it waits (may be empty).
  std::function<void()> tick;
};

/// How a pool ended.
struct PoolEnd {
  std::size_t delivered = 0;       ///< results the consumer took
  bool stopped = false;            ///< the stop flag was seen set
  bool ended_by_consumer = false;  ///< the consumer returned false
};

/// The pool on indices: `work(i, halt)` does item i and keeps its result itself; `take(i)` is
/// the consumer's turn for item i, on the calling thread, and returns false when it wants no
/// more (the pool then halts). `halt` is set when the pool ends (stop, the consumer, an
/// error): pass it to whatever runs long (run::drive_on). An exception from `work` reaches
/// the caller, in the place of that item's result (so in order, for PoolOrder::by_index);
/// the pool then halts and joins its threads before rethrowing, as for an exception from
/// `take` or `tick`.
PoolEnd run_pool_indices(std::size_t count, const PoolOptions& options,
                         const std::function<void(std::size_t, const std::atomic<bool>*)>& work,
                         const std::function<bool(std::size_t)>& take);

/// The pool with results: `work(i, halt)` returns item i's result, `deliver(i, result)` takes
/// it on the calling thread (false: no more). See run_pool_indices.
template <class Result>
PoolEnd run_pool(std::size_t count, const PoolOptions& options,
                 const std::function<Result(std::size_t, const std::atomic<bool>*)>& work,
                 const std::function<bool(std::size_t, Result&&)>& deliver) {
  std::mutex mu;
  std::map<std::size_t, Result> done;  // finished, not yet delivered
  return run_pool_indices(
      count, options,
      [&](std::size_t i, const std::atomic<bool>* halt) {
        Result r = work(i, halt);
        const std::lock_guard lock(mu);
        done.emplace(i, std::move(r));
      },
      [&](std::size_t i) {
        Result r;
        {
          const std::lock_guard lock(mu);
          const auto it = done.find(i);
          r = std::move(it->second);
          done.erase(it);
        }
        return deliver(i, std::move(r));
      });
}

}  // namespace overtake::batch
